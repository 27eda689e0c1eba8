#include "server/pacs/pacs_endpoint.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

class PacsEndpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("vpm-endpoints-" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    Write("pw", "  s3cret-Pa55word \n");
    Write("token", "tok-123456789\n");
    Write("empty", " \n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  Result<std::vector<PacsEndpoint>> Parse(const std::string& text) {
    return ParsePacsEndpoints(text, dir_, "endpoints.json");
  }
  fs::path dir_;
};

TEST_F(PacsEndpointTest, ReadsSecretsFromFilesRelativeToTheFile) {
  auto endpoints = Parse(R"([
    {"name": "orthanc", "dicomweb": "http://127.0.0.1:8042/dicom-web/", "username": "vpm",
     "password_file": "pw", "users": ["alice", "bob"]},
    {"name": "cloud", "dicomweb": "https://pacs.example/dicomweb", "bearer_token_file": "token",
     "users": ["*"]}])");
  ASSERT_TRUE(endpoints.ok()) << endpoints.status();
  ASSERT_EQ(endpoints->size(), 2u);
  const PacsEndpoint& o = (*endpoints)[0];
  EXPECT_EQ(o.dicomweb_url, "http://127.0.0.1:8042/dicom-web");
  EXPECT_EQ(o.password, "s3cret-Pa55word");
  EXPECT_TRUE(o.AllowsUser("alice"));
  EXPECT_FALSE(o.AllowsUser("carol"));
  EXPECT_FALSE(o.AllowsUser(""));
  EXPECT_EQ((*endpoints)[1].bearer_token, "tok-123456789");
  EXPECT_TRUE((*endpoints)[1].AllowsUser("carol"));
}

TEST_F(PacsEndpointTest, RejectsBadEntriesWithoutQuotingSecrets) {
  const std::vector<std::string> bad = {
      "{}",
      "[]",
      "not json",
      R"([{"dicomweb": "http://h/x", "users": ["a"]}])",
      R"([{"name": "../x", "dicomweb": "http://h/x", "users": ["a"]}])",
      R"([{"name": "a", "dicomweb": "ftp://h/x", "users": ["a"]}])",
      R"([{"name": "a", "dicomweb": "http://vpm:s3cret@h/x", "users": ["a"]}])",
      R"([{"name": "a", "dicomweb": "http://h/x"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": []}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"], "password": "x"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"], "username": "u"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"], "username": "u", "password_file": "missing"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"], "username": "u", "password_file": "empty"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"], "username": "u", "password_file": "pw", "bearer_token_file": "token"}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "users": ["a"]}, {"name": "a", "dicomweb": "http://h/y", "users": ["a"]}])",
  };
  for (const std::string& text : bad) {
    auto endpoints = Parse(text);
    ASSERT_FALSE(endpoints.ok()) << text;
    EXPECT_TRUE(absl::IsInvalidArgument(endpoints.status())) << text;
    EXPECT_EQ(endpoints.status().message().find("s3cret"), std::string_view::npos) << text;
    EXPECT_EQ(endpoints.status().message().find("tok-123"), std::string_view::npos) << text;
  }
}

TEST_F(PacsEndpointTest, ReadsReceiveAndMoveEndpoints) {
  auto endpoints = Parse(R"([
    {"name": "inbox", "receive": true, "from": ["CT01"], "users": ["alice"]},
    {"name": "pacs", "dimse": "ORTHANC@127.0.0.1:4242", "retrieve": "move",
     "move_destination": "VPM", "users": ["*"]},
    {"name": "get", "dimse": "ORTHANC@127.0.0.1:4242", "retrieve": "get", "users": ["*"]}])");
  ASSERT_TRUE(endpoints.ok()) << endpoints.status();
  const PacsEndpoint& inbox = (*endpoints)[0];
  EXPECT_TRUE(inbox.receive);
  EXPECT_EQ(inbox.receive_from, std::vector<std::string>{"CT01"});
  EXPECT_TRUE(inbox.dimse_host.empty());
  EXPECT_TRUE((*endpoints)[1].retrieve_by_move);
  EXPECT_EQ((*endpoints)[1].move_destination, "VPM");
  EXPECT_FALSE((*endpoints)[2].retrieve_by_move);
}

TEST_F(PacsEndpointTest, RefusesMalformedReceiveAndMoveEntries) {
  const std::vector<std::string> bad = {
      R"([{"name": "a", "receive": false, "users": ["a"]}])",
      R"([{"name": "a", "receive": true}])",
      R"([{"name": "a", "receive": true, "from": "CT01", "users": ["a"]}])",
      R"([{"name": "a", "receive": true, "from": ["AN AE TITLE TOO LONG"], "users": ["a"]}])",
      R"([{"name": "a", "receive": true, "dimse": "X@h:1", "users": ["a"]}])",
      R"([{"name": "a", "receive": true, "dicomweb": "http://h/x", "users": ["a"]}])",
      R"([{"name": "a", "dimse": "X@h:1", "retrieve": "move", "users": ["a"]}])",
      R"([{"name": "a", "dimse": "X@h:1", "retrieve": "push", "users": ["a"]}])",
      R"([{"name": "a", "dimse": "X@h:1", "move_destination": "VPM", "users": ["a"]}])",
      R"([{"name": "a", "dimse": "X@h:1", "from": ["X"], "users": ["a"]}])",
      R"([{"name": "a", "dicomweb": "http://h/x", "retrieve": "move", "users": ["a"]}])",
  };
  for (const std::string& text : bad) {
    auto endpoints = Parse(text);
    ASSERT_FALSE(endpoints.ok()) << text;
    EXPECT_TRUE(absl::IsInvalidArgument(endpoints.status())) << text;
  }
}

}  // namespace
}  // namespace vpm::pacs

// ListDataRoot (issue 27, "the data root can be browsed by users allowed
// to"): a user the users file gives browse-data-root lists folders, volume
// files, DICOM folders and archives; another user is refused; "..",
// absolute paths and symlinks out of the root are refused or shown as not
// openable; a FIFO is listed as not openable and never opened; messages
// never name the root; a listed source opens with LoadVolume.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>

#include "tests/service/two_users.h"

namespace vpm::service::testing {
namespace {

namespace fs = std::filesystem;


class DataRootBrowseTest : public TwoUsersTest {
 protected:
  void SetUp() override {
    const std::string tag = std::to_string(::getpid());
    root_ = fs::temp_directory_path() / ("vpm-browse-root-" + tag);
    outside_ = fs::temp_directory_path() / ("vpm-browse-outside-" + tag);
    fs::remove_all(root_);
    fs::remove_all(outside_);
    fs::create_directories(root_ / "cases" / "ct");
    fs::create_directories(root_ / "empty");
    fs::create_directories(outside_ / "secret");
    std::ofstream(root_ / "cases" / "notes.txt") << "hello";
    std::ofstream(root_ / ".hidden.nii") << "x";
    fs::copy_file(SourceData() / "ct-abdomen-kidney" / "ct_abdomen.nii.gz",
                  root_ / "cases" / "kidney.nii.gz");
    std::ofstream(root_ / "cases" / "bundle.zip") << "PK";
    int copied = 0;
    for (const auto& entry : fs::directory_iterator(SourceData() / "ct-philips-tilt")) {
      if (entry.path().filename().string().starts_with("I") && copied < 3) {
        fs::copy_file(entry.path(), root_ / "cases" / "ct" / entry.path().filename());
        ++copied;
      }
    }
    fs::create_symlink(outside_ / "secret", root_ / "escape");
    fs::create_symlink(root_ / "cases", root_ / "cases-link");
    ASSERT_EQ(::mkfifo((root_ / "cases" / "pipe.nii").c_str(), 0600), 0);
    // The third user: alice may browse, bob and default may not.
    dir_ = fs::temp_directory_path() / ("vpm-browse-users-" + tag);
    fs::create_directories(dir_);
    const fs::path users = dir_ / "users.txt";
    std::ofstream(users) << "alice " << HashToken(kAliceToken) << " browse-data-root\nbob "
                         << HashToken(kBobToken) << "\n";
    ServerOptions options = SmallServerOptions();
    options.data_root = root_.string();
    options.users_file = users.string();
    StartServer(options);
  }
  void TearDown() override {
    TwoUsersTest::TearDown();
    fs::remove_all(root_);
    fs::remove_all(outside_);
  }

  grpc::Status List(const std::string& token, const std::string& path,
                    v3::ListDataRootResponse* out) {
    v3::ListDataRootRequest request;
    request.set_path(path);
    auto context = Context(token);
    return stub_->ListDataRoot(context.get(), request, out);
  }

  static const v3::DataRootEntry* Find(const v3::ListDataRootResponse& r, const std::string& name) {
    for (const v3::DataRootEntry& e : r.entries()) {
      if (e.name() == name) return &e;
    }
    return nullptr;
  }

  fs::path root_, outside_;
};

TEST_F(DataRootBrowseTest, AllowedUserListsKindsFoldersFirst) {
  v3::ListDataRootResponse root;
  grpc::Status status = List(kAliceToken, "", &root);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(root.path(), "");
  EXPECT_EQ(Find(root, ".hidden.nii"), nullptr);
  ASSERT_NE(Find(root, "cases"), nullptr);
  EXPECT_EQ(Find(root, "cases")->kind(), v3::DataRootEntry::FOLDER);
  EXPECT_EQ(Find(root, "cases-link")->kind(), v3::DataRootEntry::FOLDER);  // inside the root
  ASSERT_NE(Find(root, "escape"), nullptr);
  EXPECT_EQ(Find(root, "escape")->kind(), v3::DataRootEntry::NOT_OPENABLE);
  EXPECT_EQ(Find(root, "escape")->source(), "");

  v3::ListDataRootResponse cases;
  status = List(kAliceToken, "cases/", &cases);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(cases.path(), "cases");
  ASSERT_GE(cases.entries_size(), 5);
  EXPECT_EQ(cases.entries(0).name(), "ct");  // folders first
  EXPECT_EQ(cases.entries(0).kind(), v3::DataRootEntry::DICOM_FOLDER);
  EXPECT_EQ(cases.entries(0).source(), "cases/ct");
  const v3::DataRootEntry* kidney = Find(cases, "kidney.nii.gz");
  ASSERT_NE(kidney, nullptr);
  EXPECT_EQ(kidney->kind(), v3::DataRootEntry::VOLUME_FILE);
  EXPECT_EQ(kidney->source(), "cases/kidney.nii.gz");
  EXPECT_GT(kidney->size_bytes(), 1000);
  EXPECT_GT(kidney->modified_unix_ms(), int64_t{1500000000000});
  EXPECT_EQ(Find(cases, "bundle.zip")->kind(), v3::DataRootEntry::ARCHIVE);
  EXPECT_EQ(Find(cases, "notes.txt")->kind(), v3::DataRootEntry::OTHER_FILE);
  EXPECT_EQ(Find(cases, "notes.txt")->source(), "");
  ASSERT_NE(Find(cases, "pipe.nii"), nullptr);  // listed, never opened
  EXPECT_EQ(Find(cases, "pipe.nii")->kind(), v3::DataRootEntry::NOT_OPENABLE);
  EXPECT_EQ(Find(cases, "pipe.nii")->source(), "");

  // What the listing offers opens.
  v3::LoadVolumeRequest load;
  load.set_source(cases.entries(0).source());
  v3::VolumeInfo info;
  auto context = Context(kAliceToken);
  status = stub_->LoadVolume(context.get(), load, &info);
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(DataRootBrowseTest, OtherUsersAreRefused) {
  v3::ListDataRootResponse out;
  grpc::Status status = List(kBobToken, "", &out);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(status.error_message().find("browse-data-root"), std::string::npos)
      << status.error_message();
  EXPECT_EQ(out.entries_size(), 0);
}

TEST_F(DataRootBrowseTest, EscapesAreRefusedWithoutNamingTheRoot) {
  struct Case {
    std::string path;
    grpc::StatusCode code;
  };
  for (const Case& c : std::vector<Case>{{"..", grpc::StatusCode::INVALID_ARGUMENT},
                                         {"cases/../..", grpc::StatusCode::INVALID_ARGUMENT},
                                         {root_.string(), grpc::StatusCode::INVALID_ARGUMENT},
                                         {"escape", grpc::StatusCode::PERMISSION_DENIED},
                                         {"missing", grpc::StatusCode::NOT_FOUND},
                                         {"cases/notes.txt", grpc::StatusCode::INVALID_ARGUMENT},
                                         {"cases/pipe.nii", grpc::StatusCode::INVALID_ARGUMENT}}) {
    v3::ListDataRootResponse out;
    grpc::Status status = List(kAliceToken, c.path, &out);
    EXPECT_EQ(status.error_code(), c.code) << c.path << ": " << status.error_message();
    if (c.path != root_.string()) {  // the client's own path may be quoted back
      EXPECT_EQ(status.error_message().find(root_.string()), std::string::npos)
          << status.error_message();
    }
    EXPECT_EQ(status.error_message().find(outside_.string()), std::string::npos)
        << status.error_message();
    EXPECT_EQ(out.entries_size(), 0) << c.path;
  }
}

}  // namespace
}  // namespace vpm::service::testing

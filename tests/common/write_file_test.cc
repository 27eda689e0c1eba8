#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "server/common/write_file.h"

namespace vpm {
namespace {

std::filesystem::path TempPath(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) / name;
}

TEST(WriteFile, WritesTheBytes) {
  const auto path = TempPath("write_file_bytes.bin");
  const std::string bytes("a\0b\nc", 5);
  ASSERT_TRUE(WriteFile(path, bytes).ok());
  std::ifstream file(path, std::ios::binary);
  std::stringstream read;
  read << file.rdbuf();
  EXPECT_EQ(read.str(), bytes);
}

TEST(WriteFile, FullDiskIsReportedWithThePath) {
  // /dev/full accepts the open and fails the write (or the flush on close)
  // with ENOSPC, as a full disk does.
  const Status status = WriteFile("/dev/full", std::string(1 << 16, 'x'));
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  EXPECT_NE(status.message().find("/dev/full"), std::string::npos) << status;
}

TEST(WriteFile, MissingFolderIsNotFound) {
  const Status status = WriteFile(TempPath("no/such/folder/frame.png"), "x");
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound) << status;
  EXPECT_NE(status.message().find("frame.png"), std::string::npos) << status;
}

TEST(MakeDirectories, CreatesParentsAndRefusesAPathThroughAFile) {
  const auto dir = TempPath("make_dirs/a/b");
  ASSERT_TRUE(MakeDirectories(dir).ok());
  EXPECT_TRUE(std::filesystem::is_directory(dir));
  const auto file = TempPath("make_dirs_file");
  ASSERT_TRUE(WriteFile(file, "x").ok());
  const Status status = MakeDirectories(file / "sub");
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("make_dirs_file"), std::string::npos) << status;
}

}  // namespace
}  // namespace vpm

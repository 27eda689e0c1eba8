// A DICOM series packed in an archive (extract_archive.h, ReadVolume's
// .zip/.tar/.tar.gz): read as the folder it came from; entries never
// escape; links skipped; a bomb stops at the cap; damaged or foreign files
// are InvalidArgument naming the archive, never the temporary folder, which
// is always removed.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "server/io/extract_archive.h"
#include "server/io/read_volume.h"
#include "tests/io/archive_test_util.h"
#include "tests/io/dicom_test_util.h"

namespace vpm {
namespace {

namespace fs = std::filesystem;

int TemporaryFolders() {
  int n = 0;
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path())) {
    if (e.path().filename().string().starts_with("vpm-archive-")) ++n;
  }
  return n;
}

class DicomArchiveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("vpm-archive-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "series");
    // The reader's temporary folders go to a folder of this test's own, so
    // that counting them does not see other tests' (ctest runs them at once).
    fs::create_directories(dir_ / "tmp");
    const char* tmpdir = std::getenv("TMPDIR");
    old_tmpdir_ = tmpdir != nullptr ? std::optional<std::string>(tmpdir) : std::nullopt;
    ::setenv("TMPDIR", (dir_ / "tmp").c_str(), 1);
    for (int k = 0; k < 4; ++k) {
      testing::DicomSliceSpec s;
      s.position_mm = {0.0, 0.0, 2.0 * k};
      s.instance_number = k + 1;
      ASSERT_TRUE(testing::WriteDicomSlice(dir_ / "series" / ("IM" + std::to_string(k)), s));
      slices_.push_back({"scan/IM" + std::to_string(k), testing::ReadAll(dir_ / "series" / ("IM" + std::to_string(k)))});
    }
  }
  void TearDown() override {
    if (old_tmpdir_) {
      ::setenv("TMPDIR", old_tmpdir_->c_str(), 1);
    } else {
      ::unsetenv("TMPDIR");
    }
    fs::remove_all(dir_);
  }
  fs::path dir_;
  std::optional<std::string> old_tmpdir_;
  std::vector<testing::ArchiveEntry> slices_;
};

TEST_F(DicomArchiveTest, AZipAndATarGzReadAsTheFolderTheyCameFrom) {
  const int folders = TemporaryFolders();
  auto folder = ReadVolume((dir_ / "series").string(), {});
  ASSERT_TRUE(folder.ok()) << folder.status();
  testing::WriteArchive(dir_ / "s.zip", slices_, true);
  testing::WriteArchive(dir_ / "s.tar.gz", slices_, false);
  for (const char* name : {"s.zip", "s.tar.gz"}) {
    auto packed = ReadVolume((dir_ / name).string(), {});
    ASSERT_TRUE(packed.ok()) << name << ": " << packed.status();
    EXPECT_EQ(packed->dims(), folder->dims()) << name;
    EXPECT_EQ(packed->geometry().origin_mm, folder->geometry().origin_mm) << name;
    for (int64_t n = 0; n < folder->geometry().voxel_count(); ++n) {
      ASSERT_EQ(packed->voxels()[n], folder->voxels()[n]) << name << " voxel " << n;
    }
    EXPECT_NE(packed->dicom_origin(), nullptr);
    EXPECT_EQ(packed->source(), (dir_ / name).string());
  }
  EXPECT_EQ(TemporaryFolders(), folders) << "a temporary folder was left behind";
}

TEST_F(DicomArchiveTest, EntriesNeverEscapeAndLinksAreSkipped) {
  std::vector<testing::ArchiveEntry> entries = slices_;
  entries.push_back({"../../escaped.dcm", "outside"});
  entries.push_back({"/abs/path.dcm", "absolute"});
  entries.push_back({"link", "/etc/passwd", true});
  testing::WriteArchive(dir_ / "evil.zip", entries, true);
  fs::create_directories(dir_ / "out");
  auto archive = OpenSourceFile(dir_ / "evil.zip", {});
  ASSERT_TRUE(archive.ok()) << archive.status();
  auto files = ExtractArchive(*archive, dir_ / "out", {});
  ASSERT_TRUE(files.ok()) << files.status();
  EXPECT_EQ(*files, 6);  // 4 slices and the two odd names, under names of ours; no link
  for (const auto& e : fs::directory_iterator(dir_ / "out")) {
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(e.path()))) << e.path();
    EXPECT_EQ(e.path().filename().string().size(), 6u) << e.path();
  }
  EXPECT_FALSE(fs::exists(dir_ / "escaped.dcm"));
  EXPECT_FALSE(fs::exists(dir_.parent_path() / "escaped.dcm"));
  // The series still reads: the odd files are not DICOM and are passed over.
  auto volume = ReadVolume((dir_ / "evil.zip").string(), {});
  EXPECT_TRUE(volume.ok()) << volume.status();
}

TEST_F(DicomArchiveTest, ABombStopsAtTheCapAndForeignFilesAreRefused) {
  const int folders = TemporaryFolders();
  testing::WriteArchive(dir_ / "bomb.zip", {{"zeros", std::string(8 << 20, '\0')}}, true);
  EXPECT_LT(fs::file_size(dir_ / "bomb.zip"), 1u << 20);  // compressed
  VolumeLimits small;
  small.max_bytes = 1 << 20;
  auto bomb = ReadVolume((dir_ / "bomb.zip").string(), small);
  EXPECT_EQ(bomb.status().code(), absl::StatusCode::kResourceExhausted) << bomb.status();

  std::ofstream(dir_ / "junk.zip") << "this is not an archive at all, just text";
  auto junk = ReadVolume((dir_ / "junk.zip").string(), {});
  EXPECT_EQ(junk.status().code(), absl::StatusCode::kInvalidArgument) << junk.status();
  std::ofstream(dir_ / "empty.zip").close();
  EXPECT_EQ(ReadVolume((dir_ / "empty.zip").string(), {}).status().code(),
            absl::StatusCode::kInvalidArgument);

  testing::WriteArchive(dir_ / "text.zip", {{"notes.txt", "no images here"}}, true);
  auto text = ReadVolume((dir_ / "text.zip").string(), {});
  EXPECT_EQ(text.status().code(), absl::StatusCode::kInvalidArgument) << text.status();
  EXPECT_EQ(std::string(text.status().message()).find("vpm-archive-"), std::string::npos)
      << "the temporary folder is named: " << text.status();
  EXPECT_NE(std::string(text.status().message()).find("text.zip"), std::string::npos)
      << text.status();
  // A FIFO named like an archive is refused at once (it would block a
  // reader for good), as a symlink out of the read root is.
  ASSERT_EQ(::mkfifo((dir_ / "fifo.zip").c_str(), 0600), 0);
  EXPECT_EQ(ReadVolume((dir_ / "fifo.zip").string(), {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  fs::create_directories(dir_ / "root");
  fs::create_symlink(dir_ / "text.zip", dir_ / "root" / "link.zip");
  VolumeLimits rooted;
  rooted.read_root = dir_ / "root";
  EXPECT_EQ(ReadVolume((dir_ / "root" / "link.zip").string(), rooted).status().code(),
            absl::StatusCode::kPermissionDenied);
  EXPECT_EQ(TemporaryFolders(), folders) << "a temporary folder was left behind";
}

}  // namespace
}  // namespace vpm

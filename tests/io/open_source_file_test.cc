// OpenSourceFile: only regular files, never blocking on a FIFO, and inside
// the read root (after resolving symlinks) when one is set; the detached data
// files and DICOM members that readers open go through it.
#include "server/io/open_source_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "server/io/read_file_bytes.h"
#include "server/io/read_volume.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

namespace fs = std::filesystem;
using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteText;

VolumeLimits RootedAt(const fs::path& root) {
  VolumeLimits limits;
  limits.read_root = fs::canonical(root);
  return limits;
}

TEST(OpenSourceFile, RefusesAFifoAtOnce) {
  const fs::path dir = MakeTempDir();
  const fs::path fifo = dir / "x.nii";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // Frees a reader that blocks (the bug) after 3 s, so that the test fails
  // rather than hangs.
  std::atomic<bool> done{false};
  std::thread rescue([&] {
    for (int i = 0; i < 30 && !done; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
    if (fd >= 0) ::close(fd);
  });
  const auto start = std::chrono::steady_clock::now();
  for (const VolumeLimits& limits : {VolumeLimits{}, RootedAt(dir)}) {
    Result<Volume> volume = ReadVolume(fifo.string(), limits);
    ASSERT_FALSE(volume.ok());
    EXPECT_EQ(volume.status().code(), absl::StatusCode::kInvalidArgument) << volume.status();
    EXPECT_NE(volume.status().message().find("a FIFO"), std::string::npos) << volume.status();
  }
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  done = true;
  rescue.join();
  EXPECT_LT(waited_s, 1.0);
}

TEST(OpenSourceFile, RefusesDevicesAndFolders) {
  Result<SourceFile> device = OpenSourceFile("/dev/null", {});
  ASSERT_FALSE(device.ok());
  EXPECT_EQ(device.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(device.status().message().find("a device"), std::string::npos) << device.status();
  const fs::path dir = MakeTempDir();
  Result<SourceFile> folder = OpenSourceFile(dir, {});
  ASSERT_FALSE(folder.ok());
  EXPECT_EQ(folder.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(OpenSourceFile(dir / "missing", {}).status().code(), absl::StatusCode::kNotFound);
}

TEST(OpenSourceFile, HoldsSymlinksToTheReadRoot) {
  const fs::path dir = MakeTempDir();
  fs::create_directories(dir / "root" / "sub");
  fs::create_directories(dir / "outside");
  WriteText(dir / "root" / "sub" / "inside.raw", "inside");
  WriteText(dir / "outside" / "secret.raw", "secret");
  fs::create_symlink(dir / "root" / "sub" / "inside.raw", dir / "root" / "near.raw");
  fs::create_symlink(dir / "outside" / "secret.raw", dir / "root" / "far.raw");
  fs::create_directory_symlink(dir / "outside", dir / "root" / "out");
  const VolumeLimits rooted = RootedAt(dir / "root");

  Result<std::vector<uint8_t>> near = ReadFileBytes(dir / "root" / "near.raw", rooted);
  ASSERT_TRUE(near.ok()) << near.status();
  EXPECT_EQ(std::string(near->begin(), near->end()), "inside");
  for (const fs::path& escape : {dir / "root" / "far.raw", dir / "root" / "out" / "secret.raw",
                                 dir / "root" / ".." / "outside" / "secret.raw"}) {
    Result<std::vector<uint8_t>> bytes = ReadFileBytes(escape, rooted);
    ASSERT_FALSE(bytes.ok()) << escape;
    EXPECT_EQ(bytes.status().code(), absl::StatusCode::kPermissionDenied) << bytes.status();
    EXPECT_NE(bytes.status().message().find("outside the data root"), std::string::npos);
  }
  // Without a root (the offline tools), links are followed as before.
  EXPECT_TRUE(ReadFileBytes(dir / "root" / "far.raw", {}).ok());
}

TEST(OpenSourceFile, MetaImageDataFileLinkLeadingOutIsRefused) {
  const fs::path dir = MakeTempDir();
  fs::create_directories(dir / "root");
  fs::create_directories(dir / "outside");
  WriteText(dir / "outside" / "secret.raw", std::string(16, '\1'));
  fs::create_symlink(dir / "outside" / "secret.raw", dir / "root" / "data.raw");
  WriteText(dir / "root" / "a.mhd",
            "ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\n"
            "ElementDataFile = data.raw\n");
  Result<Volume> rooted = ReadVolume((dir / "root" / "a.mhd").string(), RootedAt(dir / "root"));
  ASSERT_FALSE(rooted.ok());
  EXPECT_EQ(rooted.status().code(), absl::StatusCode::kPermissionDenied) << rooted.status();
  EXPECT_TRUE(ReadVolume((dir / "root" / "a.mhd").string(), {}).ok());
}

}  // namespace
}  // namespace vpm

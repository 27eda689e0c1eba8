// Cancellation inside the readers: a load of a large NIfTI, NRRD, MetaImage
// or DICOM series whose CancelToken (VolumeLimits::cancel) is cancelled
// halfway through stops within 100 ms with the token's status. Each case
// reads its file twice to time the whole read, then again, cancelled by
// another thread at half that time, and measures from the cancel to the
// reader's return.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <thread>

#include "server/io/read_volume.h"
#include "server/io/write_nifti.h"
#include "tests/io/dicom_test_util.h"

namespace vpm {
namespace {

namespace fs = std::filesystem;
using CancelClock = std::chrono::steady_clock;

// Dims of the NRRD and MetaImage volumes: 320^3 uint16, 62.5 MiB.
constexpr int kCancelSide = 320;

double CancelMsBetween(CancelClock::time_point a, CancelClock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

struct CancelTiming {
  double full_ms = 0.0;  // the read uncancelled
  double stop_ms = 0.0;  // from the cancel to the reader's return
  Status status;         // of the cancelled read
};

// Reads `source` whole, then again cancelled at half its time.
CancelTiming TimeCancelledRead(const std::string& source) {
  CancelTiming timing;
  // Twice, keeping the faster: the first read also fills the page cache, and
  // a cancel timed from a cold read alone can come after a warm read ends.
  timing.full_ms = 1e300;
  for (int pass = 0; pass < 2; ++pass) {
    const auto start = CancelClock::now();
    const Result<Volume> whole = ReadVolume(source, {});
    timing.full_ms = std::min(timing.full_ms, CancelMsBetween(start, CancelClock::now()));
    EXPECT_TRUE(whole.ok()) << whole.status();
  }
  CancelToken::Source cancel;
  VolumeLimits limits;
  limits.cancel = cancel.token();
  CancelClock::time_point cancelled_at;
  std::thread canceller([&] {
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(timing.full_ms / 2));
    cancelled_at = CancelClock::now();
    cancel.Cancel();
  });
  const Result<Volume> read = ReadVolume(source, limits);
  const auto returned_at = CancelClock::now();
  canceller.join();
  timing.status = read.status();
  timing.stop_ms = CancelMsBetween(cancelled_at, returned_at);
  return timing;
}

void ExpectStoppedQuickly(const char* format, const CancelTiming& timing) {
  std::printf("%s: whole read %.0f ms; cancelled halfway, stopped %.1f ms after the cancel (%s)\n",
              format, timing.full_ms, timing.stop_ms, timing.status.ToString().c_str());
  EXPECT_GT(timing.full_ms, 100.0) << format << ": the file is too small to time a cancel";
  EXPECT_EQ(timing.status.code(), absl::StatusCode::kCancelled) << timing.status;
  EXPECT_LT(timing.stop_ms, 100.0) << format;
}

fs::path CancelTempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("vpm-read-cancel-" + std::to_string(::getpid()) + "-" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// kCancelSide^3 uint16 values of low entropy (they compress well and fast),
// little-endian, compressed by zlib (level 1).
std::vector<uint8_t> CompressedCancelVoxels() {
  const size_t count = size_t(kCancelSide) * kCancelSide * kCancelSide;
  std::vector<uint16_t> values(count);
  for (size_t n = 0; n < count; ++n) values[n] = uint16_t((n / 7) % 1500);
  uLongf size = compressBound(uLong(count * 2));
  std::vector<uint8_t> out(size);
  EXPECT_EQ(compress2(out.data(), &size, reinterpret_cast<const Bytef*>(values.data()),
                      uLong(count * 2), 1),
            Z_OK);
  out.resize(size);
  return out;
}

void WriteCancelFile(const fs::path& path, const std::string& header,
                     const std::vector<uint8_t>& data) {
  std::ofstream out(path, std::ios::binary);
  out << header;
  out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
}

TEST(ReaderCancel, NiftiGzStopsWithin100Ms) {
  const fs::path dir = CancelTempDir("nifti");
  Result<Volume> volume = ReadVolume("phantom:abdomen?size=288", {});
  ASSERT_TRUE(volume.ok()) << volume.status();
  ASSERT_TRUE(WriteNifti(*volume, dir / "big.nii").ok());
  // gzip it (level 1): the reader inflates and converts.
  {
    std::ifstream in(dir / "big.nii", std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), {});
    gzFile gz = gzopen((dir / "big.nii.gz").c_str(), "wb1");
    ASSERT_NE(gz, nullptr);
    ASSERT_EQ(gzwrite(gz, bytes.data(), unsigned(bytes.size())), int(bytes.size()));
    gzclose(gz);
  }
  ExpectStoppedQuickly("NIfTI (.nii.gz)", TimeCancelledRead((dir / "big.nii.gz").string()));
  fs::remove_all(dir);
}

TEST(ReaderCancel, NrrdGzipStopsWithin100Ms) {
  const fs::path dir = CancelTempDir("nrrd");
  const std::string side = std::to_string(kCancelSide);
  WriteCancelFile(dir / "big.nrrd",
                  "NRRD0004\ntype: uint16\ndimension: 3\nsizes: " + side + " " + side + " " + side +
                      "\nspacings: 1 1 1\nencoding: gzip\nendian: little\n\n",
                  CompressedCancelVoxels());
  ExpectStoppedQuickly("NRRD (gzip)", TimeCancelledRead((dir / "big.nrrd").string()));
  fs::remove_all(dir);
}

TEST(ReaderCancel, MetaImageCompressedStopsWithin100Ms) {
  const fs::path dir = CancelTempDir("mha");
  const std::string side = std::to_string(kCancelSide);
  WriteCancelFile(dir / "big.mha",
                  "ObjectType = Image\nNDims = 3\nDimSize = " + side + " " + side + " " + side +
                      "\nElementType = MET_USHORT\nElementSpacing = 1 1 1\n"
                      "BinaryDataByteOrderMSB = False\nCompressedData = True\n"
                      "ElementDataFile = LOCAL\n",
                  CompressedCancelVoxels());
  ExpectStoppedQuickly("MetaImage (.mha, compressed)",
                       TimeCancelledRead((dir / "big.mha").string()));
  fs::remove_all(dir);
}

TEST(ReaderCancel, DicomSeriesStopsWithin100Ms) {
  const fs::path dir = CancelTempDir("dicom");
  testing::DicomSliceSpec spec;
  spec.rows = 256;
  spec.columns = 256;
  for (int k = 0; k < 240; ++k) {
    testing::DicomSliceSpec s = spec;
    s.position_mm = glm::dvec3(0.0, 0.0, 1.0 * k);
    s.instance_number = k + 1;
    s.stored.assign(size_t(s.rows) * s.columns, 0);
    for (size_t n = 0; n < s.stored.size(); ++n) s.stored[n] = int32_t((n + k) % 2000);
    ASSERT_TRUE(testing::WriteDicomSlice(dir / ("im" + std::to_string(k) + ".dcm"), s));
  }
  ExpectStoppedQuickly("DICOM (240 files)", TimeCancelledRead(dir.string()));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vpm

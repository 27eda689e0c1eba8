// The committed fuzz seeds must stay valid files: a seed that a reader
// rejects only fuzzes the error paths.
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "server/io/parse_raw_source.h"
#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"
#include "server/io/read_metaimage.h"
#include "server/io/read_nifti.h"
#include "server/io/read_nrrd.h"
#include "server/io/read_raw.h"

namespace vpm {
namespace {

namespace fs = std::filesystem;

// Seeds named regress_* reproduce fixed bugs and are expected to fail cleanly.
std::vector<fs::path> Seeds(const std::string& name, bool regressions = false) {
  const char* root = std::getenv("VPM_SOURCE_DIR");
  const fs::path dir = fs::path(root != nullptr ? root : ".") / "fuzz" / "corpus" / name;
  std::vector<fs::path> seeds;
  if (!fs::is_directory(dir)) return seeds;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().starts_with("regress_") == regressions) {
      seeds.push_back(entry.path());
    }
  }
  return seeds;
}

std::vector<uint8_t> Bytes(const fs::path& path) {
  auto bytes = ReadFileBytes(path, {});
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::vector<uint8_t>();
}

TEST(FuzzSeeds, AreValidFiles) {
  int count = 0;
  for (const fs::path& p : Seeds("nifti")) {
    EXPECT_TRUE(ReadNiftiFromMemory(Bytes(p), p.string(), {}).ok()) << p;
    ++count;
  }
  for (const std::string name : {"nrrd", "metaimage"}) {
    for (const fs::path& p : Seeds(name)) {
      const std::vector<uint8_t> bytes = Bytes(p);
      // As in the fuzz targets, a detached data file is the input itself.
      const DataFileLoader self = [&](std::string_view) -> Result<std::vector<uint8_t>> {
        return bytes;
      };
      const Result<Volume> v = name == "nrrd"
                                   ? ReadNrrdFromMemory(bytes, p.string(), {}, self)
                                   : ReadMetaImageFromMemory(bytes, p.string(), {}, self);
      EXPECT_TRUE(v.ok()) << p << ": " << v.status();
      ++count;
    }
  }
  for (const fs::path& p : Seeds("dicom")) {
    const Result<std::vector<DicomSlice>> slice = ParseDicomFrames(Bytes(p), {});
    EXPECT_TRUE(slice.ok() && slice->front().is_image) << p << ": " << slice.status();
    ++count;
  }
  for (const fs::path& p : Seeds("raw")) {
    const std::vector<uint8_t> bytes = Bytes(p);
    const std::string text(bytes.begin(), bytes.end());
    const size_t newline = text.find('\n');
    auto source = ParseRawSource(text.substr(0, newline));
    ASSERT_TRUE(source.ok()) << p << ": " << source.status();
    const std::span<const uint8_t> data = std::span<const uint8_t>(bytes).subspan(newline + 1);
    EXPECT_TRUE(ReadRawFromMemory(data, p.string(), source->options, {}).ok()) << p;
    ++count;
  }
  EXPECT_GE(count, 20) << "seed corpus missing? VPM_SOURCE_DIR=" << std::getenv("VPM_SOURCE_DIR");
}

TEST(FuzzSeeds, RegressionInputsAreRejected) {
  // Inputs on which DCMTK allocated gigabytes or looped forever before the
  // structure walk and the JPEG marker check; now plain errors.
  const std::vector<fs::path> seeds = Seeds("dicom", true);
  EXPECT_GE(seeds.size(), 5u);
  for (const fs::path& p : seeds) {
    const Result<std::vector<DicomSlice>> slice = ParseDicomFrames(Bytes(p), {});
    EXPECT_EQ(slice.status().code(), absl::StatusCode::kInvalidArgument)
        << p << ": " << slice.status();
  }
}

}  // namespace
}  // namespace vpm

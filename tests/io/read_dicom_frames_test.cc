// Enhanced multi-frame CT: one file, frames placed by functional groups.
#include <string>
#include <vector>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <gtest/gtest.h>

#include "server/io/read_dicom_series.h"
#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::DicomNumbers;
using ::vpm::testing::DicomSliceSpec;
using ::vpm::testing::MakeTempDir;

using Frame = ::vpm::testing::EnhancedFrame;

// An Enhanced CT image of `frames` (stored value of pixel n in frame f:
// 100 f + n), testing::FillEnhancedCt, native pixel data.
void WriteEnhancedCt(const std::filesystem::path& path, const std::vector<Frame>& frames,
                     bool per_frame_rescale, const std::string& number_of_frames = "") {
  DicomSliceSpec s;
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  ASSERT_TRUE(testing::FillEnhancedCt(ds, s, frames, per_frame_rescale, number_of_frames));
  std::vector<Uint16> pixels;
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int n = 0; n < s.rows * s.columns; ++n) pixels.push_back(static_cast<Uint16>(100 * f + n));
  }
  ds.putAndInsertUint16Array(DCM_PixelData, pixels.data(), pixels.size());
  ASSERT_TRUE(file.saveFile(path.c_str(), EXS_LittleEndianExplicit).good());
}

TEST(DicomFrames, ReadsAnEnhancedCtFromItsFunctionalGroups) {
  const auto dir = MakeTempDir();
  // Frames stored out of order along z; the middle one with its own rescale.
  WriteEnhancedCt(dir / "enhanced.dcm",
                  {{{0, 0, 4.0}, -1024.0}, {{0, 0, 0.0}, -1024.0}, {{0, 0, 2.0}, -1000.0}}, true);
  auto bytes = ReadFileBytes(dir / "enhanced.dcm", {});
  ASSERT_TRUE(bytes.ok());
  auto frames = ParseDicomFrames(*bytes, {});
  ASSERT_TRUE(frames.ok()) << frames.status();
  ASSERT_EQ(frames->size(), 3u);
  EXPECT_DOUBLE_EQ((*frames)[0].position_mm.z, 4.0);
  EXPECT_DOUBLE_EQ((*frames)[1].pixel_spacing_mm[1], 0.5);
  EXPECT_DOUBLE_EQ((*frames)[2].slice_thickness_mm, 2.0);

  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{4, 3, 3}));
  EXPECT_DOUBLE_EQ(v->spacing_mm().x, 0.5);
  EXPECT_DOUBLE_EQ(v->spacing_mm().y, 0.75);
  EXPECT_NEAR(v->spacing_mm().z, 2.0, 1e-9);
  EXPECT_FLOAT_EQ(v->At(1, 1, 0), 100 + 5 - 1024);  // frame 2 (z = 0)
  EXPECT_FLOAT_EQ(v->At(1, 1, 1), 200 + 5 - 1000);  // frame 3 (z = 2), its own intercept
  EXPECT_FLOAT_EQ(v->At(1, 1, 2), 0 + 5 - 1024);    // frame 1 (z = 4)
}

TEST(DicomFrames, SharedRescaleAndBadFrameCounts) {
  const auto dir = MakeTempDir();
  WriteEnhancedCt(dir / "enhanced.dcm", {{{0, 0, 0.0}}, {{0, 0, 1.5}}}, false);
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_FLOAT_EQ(v->At(0, 0, 1), 100 - 1024);
  // NumberOfFrames that disagrees with the per-frame groups.
  WriteEnhancedCt(dir / "enhanced.dcm", {{{0, 0, 0.0}}, {{0, 0, 1.5}}}, false, "3");
  auto bad = ReadDicomSeries(dir, {});
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("PerFrameFunctionalGroupsSequence has 2 items for 3"),
            absl::string_view::npos)
      << bad.status();
  // Frames over the voxel cap, refused before decoding.
  WriteEnhancedCt(dir / "enhanced.dcm", {{{0, 0, 0.0}}, {{0, 0, 1.5}}}, false, "2");
  auto bytes = ReadFileBytes(dir / "enhanced.dcm", {});
  ASSERT_TRUE(bytes.ok());
  VolumeLimits limits;
  limits.max_volume_bytes = 20 * 2;  // 2 frames of 12
  auto capped = ParseDicomFrames(*bytes, limits);
  EXPECT_EQ(capped.status().code(), absl::StatusCode::kResourceExhausted) << capped.status();
}

}  // namespace
}  // namespace vpm

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

struct Frame {
  glm::dvec3 position_mm{0.0};
  double intercept = -1024.0;  // written per frame when `per_frame_rescale`
};

// An Enhanced CT image of `frames` (stored value of pixel n in frame f:
// 100 f + n) with PixelSpacing, SliceThickness and ImageOrientationPatient in
// the shared functional groups and ImagePositionPatient (and, when asked,
// the rescale) per frame. Top-level geometry attributes are absent, as in
// the standard's enhanced IODs.
void WriteEnhancedCt(const std::filesystem::path& path, const std::vector<Frame>& frames,
                     bool per_frame_rescale, const std::string& number_of_frames = "") {
  DicomSliceSpec s;
  s.sop_class_uid = UID_EnhancedCTImageStorage;
  s.with_position = false;
  s.with_pixel_data = false;
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  testing::FillDicomSlice(ds, s);
  ds.findAndDeleteElement(DCM_PixelSpacing);
  ds.findAndDeleteElement(DCM_ImageOrientationPatient);
  ds.findAndDeleteElement(DCM_RescaleIntercept);
  ds.findAndDeleteElement(DCM_RescaleSlope);
  ds.putAndInsertString(DCM_NumberOfFrames, number_of_frames.empty()
                                                ? std::to_string(frames.size()).c_str()
                                                : number_of_frames.c_str());
  DcmItem* shared = nullptr;
  ASSERT_TRUE(ds.findOrCreateSequenceItem(DCM_SharedFunctionalGroupsSequence, shared, -2).good());
  DcmItem* measures = nullptr;
  ASSERT_TRUE(shared->findOrCreateSequenceItem(DCM_PixelMeasuresSequence, measures, -2).good());
  measures->putAndInsertString(DCM_PixelSpacing, "0.75\\0.5");
  measures->putAndInsertString(DCM_SliceThickness, "2");
  DcmItem* orientation = nullptr;
  ASSERT_TRUE(
      shared->findOrCreateSequenceItem(DCM_PlaneOrientationSequence, orientation, -2).good());
  orientation->putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0\\1\\0");
  DcmItem* transform = nullptr;
  if (!per_frame_rescale) {
    ASSERT_TRUE(
        shared->findOrCreateSequenceItem(DCM_PixelValueTransformationSequence, transform, -2)
            .good());
    transform->putAndInsertString(DCM_RescaleSlope, "1");
    transform->putAndInsertString(DCM_RescaleIntercept, "-1024");
  }
  std::vector<Uint16> pixels;
  for (size_t f = 0; f < frames.size(); ++f) {
    DcmItem* group = nullptr;
    ASSERT_TRUE(
        ds.findOrCreateSequenceItem(DCM_PerFrameFunctionalGroupsSequence, group, -2).good());
    DcmItem* position = nullptr;
    ASSERT_TRUE(group->findOrCreateSequenceItem(DCM_PlanePositionSequence, position, -2).good());
    const glm::dvec3& p = frames[f].position_mm;
    position->putAndInsertString(DCM_ImagePositionPatient, DicomNumbers({p.x, p.y, p.z}).c_str());
    if (per_frame_rescale) {
      ASSERT_TRUE(
          group->findOrCreateSequenceItem(DCM_PixelValueTransformationSequence, transform, -2)
              .good());
      transform->putAndInsertString(DCM_RescaleSlope, "1");
      transform->putAndInsertString(DCM_RescaleIntercept,
                                    DicomNumbers({frames[f].intercept}).c_str());
    }
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

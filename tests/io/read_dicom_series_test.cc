#include "server/io/read_dicom_series.h"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"
#include "tests/io/dicom_test_util.h"
#include "tests/io/io_test_util.h"

namespace vpm {
namespace {

using ::vpm::testing::DicomSliceSpec;
using ::vpm::testing::MakeTempDir;
using ::vpm::testing::WriteDicomSlice;

void ExpectError(const Result<Volume>& v, absl::StatusCode code, const std::string& fragment) {
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), code) << v.status();
  EXPECT_NE(v.status().message().find(fragment), absl::string_view::npos) << v.status();
}

// Writes slices k = 0..count-1 at `origin + k * gap * normal`, files named in
// reverse order so that sorting by position is exercised.
std::filesystem::path WriteSeries(const DicomSliceSpec& base, int count, double gap,
                                  const glm::dvec3& origin, const std::string& dir_name = "") {
  const auto dir = dir_name.empty() ? MakeTempDir() : MakeTempDir() / dir_name;
  std::filesystem::create_directories(dir);
  const auto& o = base.orientation;
  const glm::dvec3 normal = glm::cross(glm::dvec3(o[0], o[1], o[2]), glm::dvec3(o[3], o[4], o[5]));
  for (int k = 0; k < count; ++k) {
    DicomSliceSpec s = base;
    s.position_mm = origin + (k * gap) * normal;
    s.stored.clear();
    for (int n = 0; n < s.rows * s.columns; ++n) s.stored.push_back(100 * k + n);
    EXPECT_TRUE(WriteDicomSlice(dir / ("im" + std::to_string(count - k) + ".dcm"), s));
  }
  return dir;
}

TEST(DicomSeriesReader, StacksSlicesAlongNormalWithRescale) {
  DicomSliceSpec s;
  const double c = std::cos(glm::radians(30.0)), sn = std::sin(glm::radians(30.0));
  s.orientation = {c, sn, 0, -sn, c, 0};  // rotated 30 degrees about z
  s.slope = 2.0;
  s.intercept = -1024.0;
  const glm::dvec3 origin(-100.0, 50.0, 20.0);
  const auto dir = WriteSeries(s, 4, 2.5, origin);
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  EXPECT_EQ(g.dims, (std::array<int64_t, 3>{4, 3, 4}));
  EXPECT_NEAR(g.spacing_mm.x, 0.5, 1e-9);   // PixelSpacing[1]: between columns
  EXPECT_NEAR(g.spacing_mm.y, 0.75, 1e-9);  // PixelSpacing[0]: between rows
  EXPECT_NEAR(g.spacing_mm.z, 2.5, 1e-5);
  EXPECT_NEAR(glm::distance(g.origin_mm, origin), 0.0, 1e-5);
  EXPECT_NEAR(glm::distance(g.direction[0], glm::dvec3(c, sn, 0)), 0.0, 1e-5);
  EXPECT_NEAR(glm::distance(g.direction[2], glm::dvec3(0, 0, 1)), 0.0, 1e-5);
  // Voxel (i, j, k) holds 2 * (100 k + i + 4 j) - 1024.
  EXPECT_EQ(v->At(1, 2, 3), 2.0f * (300 + 1 + 8) - 1024.0f);
  EXPECT_EQ(v->At(0, 0, 0), -1024.0f);
  EXPECT_EQ(v->source(), dir.string());
}

TEST(DicomSeriesReader, HandlesBitDepthsAndSignedness) {
  struct Case {
    int bits_allocated, bits_stored;
    bool is_signed;
    int32_t stored;
    float expected;
  };
  const Case cases[] = {{8, 8, false, 200, 200.0f},
                        {16, 16, false, 60000, 60000.0f},
                        {16, 16, true, 0xFFFE, -2.0f},
                        {16, 12, true, 0x0FFF, -1.0f},     // 12-bit signed -1
                        {16, 12, true, 0xF7FF, 2047.0f}};  // bits above 12 ignored
  for (const Case& c : cases) {
    DicomSliceSpec s;
    s.rows = 1;
    s.columns = 1;
    s.bits_allocated = c.bits_allocated;
    s.bits_stored = c.bits_stored;
    s.is_signed = c.is_signed;
    s.intercept = 0.0;
    s.stored = {c.stored};
    const auto dir = MakeTempDir();
    ASSERT_TRUE(WriteDicomSlice(dir / "one.dcm", s));
    auto v = ReadDicomSeries(dir, {});
    ASSERT_TRUE(v.ok()) << v.status();
    EXPECT_EQ(v->values()[0], c.expected) << c.bits_allocated << "/" << c.bits_stored;
  }
}

TEST(DicomSeriesReader, ReadsImplicitAndCompressedTransferSyntaxes) {
  for (E_TransferSyntax xfer : {EXS_LittleEndianImplicit, EXS_RLELossless, EXS_JPEGProcess14SV1}) {
    DicomSliceSpec s;
    s.transfer_syntax = xfer;
    s.is_signed = false;
    s.bits_stored = 12;
    const auto dir = WriteSeries(s, 3, 1.0, glm::dvec3(0.0));
    auto v = ReadDicomSeries(dir, {});
    ASSERT_TRUE(v.ok()) << DcmXfer(xfer).getXferName() << ": " << v.status();
    EXPECT_EQ(v->At(3, 2, 2), 200.0f + 3 + 8 - 1024.0f) << DcmXfer(xfer).getXferName();
  }
}

TEST(DicomSeriesReader, SkipsNonDicomAndNonImageFiles) {
  const auto dir = WriteSeries(DicomSliceSpec{}, 2, 1.0, glm::dvec3(0.0));
  testing::WriteText(dir / "README.txt", "not an image");
  DicomSliceSpec report;
  report.with_pixel_data = false;
  ASSERT_TRUE(WriteDicomSlice(dir / "DICOMDIR", report));
  // A large non-DICOM file is skipped unread: it does not count to the cap.
  testing::WriteBytes(dir / "report.pdf", std::vector<uint8_t>(20000, 0x25));
  VolumeLimits limits;
  limits.max_bytes = 10000;
  auto v = ReadDicomSeries(dir, limits);
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims()[2], 2);
}

TEST(DicomSeriesReader, SingleSliceUsesSliceThickness) {
  DicomSliceSpec s;
  s.slice_thickness_mm = 3.0;
  const auto dir = MakeTempDir();
  ASSERT_TRUE(WriteDicomSlice(dir / "a.dcm", s));
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_DOUBLE_EQ(v->spacing_mm().z, 3.0);
}

// ---- Bad input ----

TEST(DicomSeriesReader, RejectsMixedSeries) {
  DicomSliceSpec s;
  const auto dir = WriteSeries(s, 2, 1.0, glm::dvec3(0.0));
  s.series_uid = "1.2.3.4.5";
  s.position_mm = glm::dvec3(0, 0, 9);
  ASSERT_TRUE(WriteDicomSlice(dir / "other.dcm", s));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument,
              "holds 2 series (UIDs 1.2.3.4.5 (1 files), 1.2.826.0.1.3680043.8.498.1 (2 files)); "
              "pass one series per folder");
}

TEST(DicomSeriesReader, RejectsUnevenSpacing) {
  DicomSliceSpec s;
  const auto dir = WriteSeries(s, 3, 1.0, glm::dvec3(0.0));
  s.position_mm = glm::dvec3(0, 0, 4.0);  // slice at 3 mm is missing
  ASSERT_TRUE(WriteDicomSlice(dir / "late.dcm", s));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "uneven slice spacing");
}

TEST(DicomSeriesReader, RejectsDuplicatePositions) {
  DicomSliceSpec s;
  const auto dir = WriteSeries(s, 3, 1.0, glm::dvec3(0.0));
  s.position_mm = glm::dvec3(0, 0, 1.0);
  ASSERT_TRUE(WriteDicomSlice(dir / "again.dcm", s));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument,
              "duplicate slice position");
}

TEST(DicomSeriesReader, RejectsTruncatedFile) {
  const auto dir = WriteSeries(DicomSliceSpec{}, 3, 1.0, glm::dvec3(0.0));
  auto bytes = ReadFileBytes(dir / "im2.dcm", {});
  ASSERT_TRUE(bytes.ok());
  bytes->resize(bytes->size() - 10);
  testing::WriteBytes(dir / "im2.dcm", *bytes);
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "im2.dcm");
  bytes->resize(200);
  testing::WriteBytes(dir / "im2.dcm", *bytes);
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "im2.dcm");
}

TEST(DicomSeriesReader, RejectsMismatchedSlices) {
  DicomSliceSpec s;
  const auto dir = WriteSeries(s, 2, 1.0, glm::dvec3(0.0));
  s.rows = 5;
  s.position_mm = glm::dvec3(0, 0, 2);
  ASSERT_TRUE(WriteDicomSlice(dir / "big.dcm", s));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "Rows/Columns");
  s.rows = 3;
  s.orientation = {0, 1, 0, 1, 0, 0};
  ASSERT_TRUE(WriteDicomSlice(dir / "big.dcm", s));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument,
              "ImageOrientationPatient");
}

TEST(DicomSeriesReader, RejectsNonOrthonormalOrientation) {
  DicomSliceSpec s;
  s.orientation = {1, 0, 0, 0.5, 0.8660254, 0};  // 60 degrees between row and column
  const auto dir = WriteSeries(s, 2, 1.0, glm::dvec3(0.0));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "orthonormal");
}

TEST(DicomSeriesReader, RejectsTiltedStackAsUnimplemented) {
  DicomSliceSpec s;
  const auto dir = MakeTempDir();
  for (int k = 0; k < 3; ++k) {
    s.position_mm = glm::dvec3(0, 0.5 * k, 1.0 * k);  // shifts along y as it rises
    ASSERT_TRUE(WriteDicomSlice(dir / ("t" + std::to_string(k) + ".dcm"), s));
  }
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kUnimplemented,
              "across the slice normal");
}

TEST(DicomSeriesReader, RejectsEmptyAndMissingFolders) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "notes.txt", "hello");
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "no DICOM images");
  ExpectError(ReadDicomSeries(dir / "nope", {}), absl::StatusCode::kNotFound, "nope");
}

TEST(DicomSeriesReader, RejectsSeriesOverCaps) {
  const auto dir = WriteSeries(DicomSliceSpec{}, 4, 1.0, glm::dvec3(0.0));
  VolumeLimits limits;
  limits.max_voxels = 30;  // 12 voxels per slice
  ExpectError(ReadDicomSeries(dir, limits), absl::StatusCode::kResourceExhausted, "cap");
  limits = {};
  limits.max_bytes = 1000;  // each file is several hundred bytes
  ExpectError(ReadDicomSeries(dir, limits), absl::StatusCode::kResourceExhausted, "cap");
}

TEST(DicomSlice, RejectsUnsupportedImagesAsUnimplemented) {
  DicomSliceSpec colour;
  colour.samples_per_pixel = 3;
  colour.bits_allocated = 8;
  colour.bits_stored = 8;
  colour.is_signed = false;
  const auto dir = MakeTempDir();
  ASSERT_TRUE(WriteDicomSlice(dir / "rgb.dcm", colour));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kUnimplemented, "SamplesPerPixel is 3");
  DicomSliceSpec frames;
  frames.number_of_frames = "2";
  ASSERT_TRUE(WriteDicomSlice(dir / "rgb.dcm", frames));
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kUnimplemented, "multi-frame");
}

TEST(DicomSlice, RejectsMissingPositionAndPlainBytes) {
  DicomSliceSpec s;
  s.with_position = false;
  const auto path = MakeTempDir() / "nopos.dcm";
  ASSERT_TRUE(WriteDicomSlice(path, s));
  auto bytes = ReadFileBytes(path, {});
  ASSERT_TRUE(bytes.ok());
  auto slice = ParseDicomSlice(*bytes, {});
  ASSERT_FALSE(slice.ok());
  EXPECT_EQ(slice.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(slice.status().message().find("ImagePositionPatient is missing"),
            absl::string_view::npos)
      << slice.status();
  const std::vector<uint8_t> junk(300, 7);
  EXPECT_EQ(ParseDicomSlice(junk, {}).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

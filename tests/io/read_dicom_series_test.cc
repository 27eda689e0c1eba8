#include "server/io/read_dicom_series.h"

#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include "server/io/list_dicom_series.h"
#include "server/io/read_dicom_slice.h"
#include "server/io/read_volume.h"
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
    EXPECT_EQ(v->voxels()[0], c.expected) << c.bits_allocated << "/" << c.bits_stored;
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

bool HasNote(const Volume& v, const std::string& fragment) {
  for (const std::string& note : v.notes()) {
    if (note.find(fragment) != std::string::npos) return true;
  }
  return false;
}

std::string Notes(const Volume& v) {
  std::string out;
  for (const std::string& note : v.notes()) out += note + "\n";
  return out;
}

// ---- Several series, localizers, secondary captures ----

TEST(DicomSeriesReader, ReadsTheLargestCtSeriesAndPicksOthersOnRequest) {
  DicomSliceSpec small;
  small.series_uid = "1.2.3.4.5";
  small.series_number = 2;
  const auto dir = WriteSeries(small, 2, 1.0, glm::dvec3(0.0));
  DicomSliceSpec big;
  big.series_number = 3;
  big.series_description = "thin axial";
  for (int k = 0; k < 4; ++k) {
    big.position_mm = glm::dvec3(0, 0, 0.5 * k);
    ASSERT_TRUE(WriteDicomSlice(dir / ("big" + std::to_string(k) + ".dcm"), big));
  }
  DicomSliceSpec mr = big;  // more voxels, but CT comes first by default
  mr.series_uid = "1.2.3.4.6";
  mr.series_number = 4;
  mr.modality = "OT";
  mr.rows = 6;
  for (int k = 0; k < 4; ++k) {
    mr.position_mm = glm::dvec3(0, 0, 0.5 * k);
    ASSERT_TRUE(WriteDicomSlice(dir / ("ot" + std::to_string(k) + ".dcm"), mr));
  }
  auto series = ListDicomSeries(dir, {});
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_EQ(series->size(), 3u);
  EXPECT_EQ((*series)[0].uid, "1.2.3.4.5");  // by SeriesNumber
  EXPECT_EQ((*series)[1].description, "thin axial");
  EXPECT_EQ((*series)[2].rows, 6);

  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims()[2], 4);
  EXPECT_DOUBLE_EQ(v->spacing_mm().z, 0.5);
  EXPECT_TRUE(HasNote(*v, "holds 3 series; read series 2 (1.2.826.0.1.3680043.8.498.1"))
      << Notes(*v);

  auto by_uid = ReadDicomSeries(dir, {}, {.series = "1.2.3.4.5"});
  ASSERT_TRUE(by_uid.ok()) << by_uid.status();
  EXPECT_EQ(by_uid->dims()[2], 2);
  auto by_index = ReadDicomSeries(dir, {}, {.series = "3"});
  ASSERT_TRUE(by_index.ok()) << by_index.status();
  EXPECT_EQ(by_index->dims()[1], 6);

  ExpectError(ReadDicomSeries(dir, {}, {.series = "9.9.9"}), absl::StatusCode::kInvalidArgument,
              "no series \"9.9.9\" (a UID or 1..3); the folder holds 1 = 1.2.3.4.5 (CT, 2 images)");
  ExpectError(ReadDicomSeries(dir, {}, {.series = "0"}), absl::StatusCode::kInvalidArgument,
              "no series \"0\"");
}

// Text is UTF-8 whatever the file's character set: converted from a
// declared ISO 8859-1 (ISO_IR 100) or 8859-2 (ISO_IR 101), read as Latin-1
// where none is declared, kept where it is UTF-8 (ISO_IR 192).
TEST(DicomSeriesReader, DescriptionsAreUtf8WhateverTheFilesCharacterSet) {
  const std::string utf8 =
      "Sch\xc3\xa4"
      "del";  // Schädel
  struct Case {
    const char* charset;
    std::string description;
  };
  const Case cases[] = {{"ISO_IR 100",
                         "Sch\xe4"
                         "del"},
                        {"",
                         "Sch\xe4"
                         "del"},
                        {"ISO_IR 192", utf8},
                        {"ISO_IR 101",
                         "\xa3\xf3"
                         "d\xbc"}};
  const auto dir = MakeTempDir();
  for (int n = 0; n < 4; ++n) {
    DicomSliceSpec s;
    s.series_uid = "1.2.3.4." + std::to_string(n + 1);
    s.series_number = n + 1;
    s.series_description = cases[n].description;
    if (*cases[n].charset != 0) s.more = {{DCM_SpecificCharacterSet, cases[n].charset}};
    for (int k = 0; k < 2; ++k) {
      s.position_mm = glm::dvec3(0.0, 0.0, k);
      ASSERT_TRUE(WriteDicomSlice(dir / ("s" + std::to_string(n) + "_" + std::to_string(k)), s));
    }
  }
  const auto listed = ListDicomSeries(dir, {});
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_EQ(listed->size(), 4u);
  for (int n = 0; n < 3; ++n) EXPECT_EQ((*listed)[n].description, utf8) << (*listed)[n].uid;
  // Latin-2 (ISO_IR 101) is not Latin-1: converted, not guessed ("£ód¼").
  EXPECT_EQ((*listed)[3].description,
            "\xc5\x81\xc3\xb3"
            "d\xc5\xba");  // Łódź
}

TEST(DicomSeriesReader, NeverStacksLocalizersOrSecondaryCaptures) {
  DicomSliceSpec s;
  const auto dir = WriteSeries(s, 3, 1.0, glm::dvec3(0.0));
  DicomSliceSpec scout = s;  // same series UID, as some scanners write them
  scout.image_type = "ORIGINAL\\PRIMARY\\LOCALIZER";
  scout.orientation = {0, 1, 0, 0, 0, -1};
  ASSERT_TRUE(WriteDicomSlice(dir / "scout.dcm", scout));
  DicomSliceSpec capture;
  capture.series_uid = "1.2.3.4.7";
  capture.sop_class_uid = UID_SecondaryCaptureImageStorage;
  capture.samples_per_pixel = 3;  // a screenshot: colour, which a slice could not be
  capture.bits_allocated = capture.bits_stored = 8;
  capture.is_signed = false;
  capture.with_position = false;
  ASSERT_TRUE(WriteDicomSlice(dir / "capture.dcm", capture));
  auto series = ListDicomSeries(dir, {});
  ASSERT_TRUE(series.ok()) << series.status();
  ASSERT_EQ(series->size(), 3u);
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{4, 3, 3}));
  size_t scout_index = 0;
  for (size_t n = 0; n < series->size(); ++n) {
    if ((*series)[n].not_a_volume_reason == "localizer") scout_index = n + 1;
  }
  ASSERT_GT(scout_index, 0u);
  ExpectError(ReadDicomSeries(dir, {}, {.series = std::to_string(scout_index)}),
              absl::StatusCode::kInvalidArgument, "is a localizer, not a volume");
  std::filesystem::remove(dir / "im1.dcm");
  std::filesystem::remove(dir / "im2.dcm");
  std::filesystem::remove(dir / "im3.dcm");
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument,
              "holds no series of slices, only localizers or secondary captures");
}

// ---- Uneven gaps and tilted stacks: resampled ----

TEST(DicomSeriesReader, ResamplesUnevenSpacingToTheSmallestGap) {
  DicomSliceSpec s;
  s.intercept = 0.0;
  const auto dir = WriteSeries(s, 3, 1.0, glm::dvec3(0.0));  // slices 0, 1, 2 mm: 100 k + n
  s.position_mm = glm::dvec3(0, 0, 8.0);  // a 6 mm hole: slices missing
  s.stored.clear();
  for (int n = 0; n < 12; ++n) s.stored.push_back(800 + n);
  ASSERT_TRUE(WriteDicomSlice(dir / "late.dcm", s));
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims(), (std::array<int64_t, 3>{4, 3, 9}));
  EXPECT_DOUBLE_EQ(v->spacing_mm().z, 1.0);
  EXPECT_FLOAT_EQ(v->At(1, 2, 1), 100 + 9);
  EXPECT_FLOAT_EQ(v->At(1, 2, 5), 200 + 9 + 0.5f * 600);  // halfway from 2 mm to 8 mm
  EXPECT_FLOAT_EQ(v->At(1, 2, 8), 800 + 9);
  EXPECT_TRUE(HasNote(*v, "slice gaps 1 to 6 mm: resampled to 1 mm")) << Notes(*v);
  EXPECT_TRUE(HasNote(*v, "over 5 times the smallest")) << Notes(*v);

  auto coarse = ReadDicomSeries(dir, {}, {.spacing_mm = 2.0});
  ASSERT_TRUE(coarse.ok()) << coarse.status();
  EXPECT_EQ(coarse->dims()[2], 5);
  EXPECT_FLOAT_EQ(coarse->At(1, 2, 2), 200 + 9 + 2.0f / 6.0f * 600);  // at 4 mm
}

TEST(DicomSeriesReader, ExplicitSpacingResamplesAnEvenStack) {
  const auto dir = WriteSeries(DicomSliceSpec{}, 3, 2.0, glm::dvec3(0.0));
  auto v = ReadVolume(dir.string() + "?spacing=0.5", {});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->dims()[2], 9);
  EXPECT_DOUBLE_EQ(v->spacing_mm().z, 0.5);
  EXPECT_FLOAT_EQ(v->At(0, 0, 1), -1024 + 25);  // a quarter of the way to the next slice
  EXPECT_TRUE(HasNote(*v, "slice gap 2 mm: resampled to 0.5 mm")) << Notes(*v);
  ExpectError(ReadVolume(dir.string() + "?spacing=-1", {}), absl::StatusCode::kInvalidArgument,
              "spacing must be a number of mm > 0");
  ExpectError(ReadVolume(dir.string() + "?serie=1", {}), absl::StatusCode::kInvalidArgument,
              "unknown key \"serie\"");
}

TEST(DicomSeriesReader, ResamplesATiltedStackOntoTheOrthogonalGrid) {
  DicomSliceSpec s;
  s.intercept = 0.0;
  const auto dir = MakeTempDir();
  for (int k = 0; k < 3; ++k) {
    s.stored.clear();
    for (int n = 0; n < 12; ++n) s.stored.push_back(500 + n);
    if (k == 0) s.stored[0] = 100;  // the series' minimum: the fill outside the stack
    s.position_mm = glm::dvec3(0, 0.75 * k, 1.0 * k);  // one row further per slice
    ASSERT_TRUE(WriteDicomSlice(dir / ("t" + std::to_string(k) + ".dcm"), s));
  }
  auto v = ReadDicomSeries(dir, {});
  ASSERT_TRUE(v.ok()) << v.status();
  const VolumeGeometry& g = v->geometry();
  EXPECT_EQ(g.dims, (std::array<int64_t, 3>{4, 5, 3}));  // 2 rows more, to hold the shift
  EXPECT_NEAR(g.spacing_mm.y, 0.75, 1e-9);
  EXPECT_NEAR(g.spacing_mm.z, 1.0, 1e-5);
  EXPECT_NEAR(glm::distance(g.direction[2], glm::dvec3(0, 0, 1)), 0.0, 1e-9);
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 5; ++j) {
      const bool inside = j >= k && j < k + 3;
      EXPECT_FLOAT_EQ(v->At(2, j, k), inside ? 502.0f + 4 * (j - k) : 100.0f) << j << " " << k;
    }
  }
  EXPECT_TRUE(HasNote(*v, "gantry tilt 36.9 deg")) << Notes(*v);
}

TEST(DicomSeriesReader, RejectsEmptyAndMissingFolders) {
  const auto dir = MakeTempDir();
  testing::WriteText(dir / "notes.txt", "hello");
  ExpectError(ReadDicomSeries(dir, {}), absl::StatusCode::kInvalidArgument, "no DICOM images");
  ExpectError(ReadDicomSeries(dir / "nope", {}), absl::StatusCode::kNotFound, "nope");
  // An export's top folder: the series lie in subfolders, which are named.
  const auto series = WriteSeries(DicomSliceSpec{}, 2, 1.0, glm::dvec3(0.0), "SE000");
  const auto top = series.parent_path();
  for (const char* name : {"SE001", "SE002", "SE003"})
    std::filesystem::create_directory(top / name);
  ExpectError(ReadDicomSeries(top, {}), absl::StatusCode::kInvalidArgument,
              "holds no DICOM images (0 files checked); its 4 subfolders (SE000, SE001, SE002, "
              "...) are not read: give the folder that holds the series' files");
  std::filesystem::remove_all(top / "SE001");
  std::filesystem::remove_all(top / "SE002");
  std::filesystem::remove_all(top / "SE003");
  ExpectError(ReadDicomSeries(top, {}), absl::StatusCode::kInvalidArgument,
              "its 1 subfolder (SE000) is not read");
  EXPECT_TRUE(ReadDicomSeries(series, {}).ok());
}

TEST(DicomSeriesReader, RejectsSeriesOverCaps) {
  const auto dir = WriteSeries(DicomSliceSpec{}, 4, 1.0, glm::dvec3(0.0));
  VolumeLimits limits;
  limits.max_volume_bytes = 30 * 2;  // 12 voxels per slice
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
  auto slice = ParseDicomFrames(*bytes, {});
  ASSERT_FALSE(slice.ok());
  EXPECT_EQ(slice.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(slice.status().message().find("ImagePositionPatient is missing"),
            absl::string_view::npos)
      << slice.status();
  const std::vector<uint8_t> junk(300, 7);
  EXPECT_EQ(ParseDicomFrames(junk, {}).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

// Series thumbnails (series_thumbnail.h): decode, window, scale and encode
// one instance, synthetic and real (tests/data's tilted CT); the middle
// instance by InstanceNumber; a DICOM without pixels answers a clear error.
#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcostrmb.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "server/pacs/dicom_json.h"
#include "server/pacs/series_thumbnail.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

fs::path SourceData() {
  const char* source = std::getenv("VPM_SOURCE_DIR");
  return source != nullptr ? fs::path(source) / "tests" / "data"
                           : fs::path(__FILE__).parent_path().parent_path() / "data";
}

// A CT slice of `columns` x `rows` int16 pixels whose value is the column
// index x 10 (a ramp from left to right), 0.5 x 1.0 mm pixels (rows 0.5 mm
// apart); with `pixels` false, no pixel data (as a structured report).
std::vector<uint8_t> SyntheticDicom(int columns, int rows, bool pixels, const char* window) {
  DcmFileFormat file;
  DcmDataset* ds = file.getDataset();
  char uid[100];
  ds->putAndInsertString(DCM_SOPClassUID, pixels ? UID_CTImageStorage : UID_BasicTextSRStorage);
  ds->putAndInsertString(DCM_SOPInstanceUID, dcmGenerateUniqueIdentifier(uid));
  ds->putAndInsertString(DCM_SeriesInstanceUID, "1.2.3.4");
  ds->putAndInsertString(DCM_StudyInstanceUID, "1.2.3");
  ds->putAndInsertString(DCM_Modality, pixels ? "CT" : "SR");
  if (pixels) {
    ds->putAndInsertUint16(DCM_Rows, static_cast<Uint16>(rows));
    ds->putAndInsertUint16(DCM_Columns, static_cast<Uint16>(columns));
    ds->putAndInsertUint16(DCM_BitsAllocated, 16);
    ds->putAndInsertUint16(DCM_BitsStored, 16);
    ds->putAndInsertUint16(DCM_HighBit, 15);
    ds->putAndInsertUint16(DCM_PixelRepresentation, 1);
    ds->putAndInsertUint16(DCM_SamplesPerPixel, 1);
    ds->putAndInsertString(DCM_PhotometricInterpretation, "MONOCHROME2");
    ds->putAndInsertString(DCM_PixelSpacing, "0.5\\1.0");
    ds->putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0\\1\\0");
    ds->putAndInsertString(DCM_ImagePositionPatient, "0\\0\\0");
    ds->putAndInsertString(DCM_RescaleSlope, "1");
    ds->putAndInsertString(DCM_RescaleIntercept, "0");
    if (window != nullptr) {
      ds->putAndInsertString(DCM_WindowCenter, window);
      ds->putAndInsertString(DCM_WindowWidth, "100");
    }
    std::vector<Sint16> values(size_t(columns) * size_t(rows));
    for (int j = 0; j < rows; ++j) {
      for (int i = 0; i < columns; ++i) values[size_t(j) * columns + i] = Sint16(i * 10);
    }
    ds->putAndInsertUint16Array(DCM_PixelData, reinterpret_cast<const Uint16*>(values.data()),
                                static_cast<unsigned long>(values.size()));
  }
  const fs::path path = fs::temp_directory_path() / ("vpm-thumb-" + std::to_string(::getpid()));
  EXPECT_TRUE(file.saveFile(path.c_str(), EXS_LittleEndianExplicit).good());
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove(path);
  return bytes;
}

// The mean and standard deviation of a decoded thumbnail's grey levels.
void GreyStats(const DecodedImage& image, double* mean, double* stddev) {
  double sum = 0, squares = 0;
  const size_t n = size_t(image.width) * size_t(image.height);
  for (size_t p = 0; p < n; ++p) {
    const double v = image.rgba[p * 4];
    sum += v;
    squares += v * v;
  }
  *mean = sum / double(n);
  *stddev = std::sqrt(std::max(0.0, squares / double(n) - *mean * *mean));
}

TEST(SeriesThumbnail, SyntheticRampKeepsAspectAndDirection) {
  // 400 columns x 300 rows of 1.0 x 0.5 mm: 400 mm wide, 150 mm high.
  const std::vector<uint8_t> dicom = SyntheticDicom(400, 300, true, nullptr);
  auto thumb = RenderSeriesThumbnail(dicom, 128, {});
  ASSERT_TRUE(thumb.ok()) << thumb.status();
  EXPECT_EQ(thumb->width, 128);
  EXPECT_EQ(thumb->height, 48);  // 128 x 150 / 400
  auto image = DecodePng(thumb->png);
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, 128);
  EXPECT_EQ(image->height, 48);
  const auto grey = [&](int x, int y) { return image->rgba[(size_t(y) * 128 + x) * 4]; };
  EXPECT_LT(grey(2, 20), 10);     // below the 1st percentile: black
  EXPECT_GT(grey(125, 20), 245);  // above the 99th: white
  EXPECT_LT(grey(40, 20), grey(80, 20));
  double mean = 0, stddev = 0;
  GreyStats(*image, &mean, &stddev);
  EXPECT_GT(stddev, 40);
}

TEST(SeriesThumbnail, OwnWindowIsUsed) {
  // Window 1000 +- 50: columns below 95 black, above 105 white.
  const std::vector<uint8_t> dicom = SyntheticDicom(200, 200, true, "1000");
  auto thumb = RenderSeriesThumbnail(dicom, 200, {});
  ASSERT_TRUE(thumb.ok()) << thumb.status();
  EXPECT_EQ(thumb->width, 200);  // 200 x 1.0 mm wide, 200 x 0.5 mm high
  EXPECT_EQ(thumb->height, 100);
  auto image = DecodePng(thumb->png);
  ASSERT_TRUE(image.ok());
  EXPECT_EQ(image->rgba[(50 * 200 + 50) * 4], 0);
  EXPECT_EQ(image->rgba[(50 * 200 + 150) * 4], 255);
}

TEST(SeriesThumbnail, RealTiltedCtSliceIsNotBlank) {
  std::vector<fs::path> slices;
  for (const auto& entry : fs::directory_iterator(SourceData() / "ct-philips-tilt")) {
    if (entry.path().filename().string().starts_with("I")) slices.push_back(entry.path());
  }
  ASSERT_FALSE(slices.empty());
  std::sort(slices.begin(), slices.end());
  std::ifstream in(slices[slices.size() / 2], std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto thumb = RenderSeriesThumbnail(bytes, 96, {});
  ASSERT_TRUE(thumb.ok()) << thumb.status();
  EXPECT_EQ(std::max(thumb->width, thumb->height), 96);
  auto image = DecodePng(thumb->png);
  ASSERT_TRUE(image.ok());
  double mean = 0, stddev = 0;
  GreyStats(*image, &mean, &stddev);
  EXPECT_GT(stddev, 20) << "mean " << mean;
  EXPECT_LT(thumb->png.size(), 32u << 10);
}

TEST(SeriesThumbnail, NoPixelsOrBadSizeIsAClearError) {
  const std::vector<uint8_t> report = SyntheticDicom(0, 0, false, nullptr);
  auto thumb = RenderSeriesThumbnail(report, 128, {});
  ASSERT_FALSE(thumb.ok());
  EXPECT_EQ(thumb.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(thumb.status().message().find("no image"), std::string_view::npos) << thumb.status();
  const std::vector<uint8_t> dicom = SyntheticDicom(32, 32, true, nullptr);
  EXPECT_EQ(RenderSeriesThumbnail(dicom, 8, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(RenderSeriesThumbnail(dicom, 257, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<uint8_t> text = {'n', 'o', 't'};
  EXPECT_EQ(RenderSeriesThumbnail(text, 128, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  // A small image keeps its own size.
  auto small = RenderSeriesThumbnail(dicom, 128, {});
  ASSERT_TRUE(small.ok()) << small.status();
  EXPECT_EQ(small->width, 32);
  EXPECT_EQ(small->height, 16);
}

TEST(SeriesThumbnail, MiddleInstanceByNumber) {
  EXPECT_EQ(MiddleInstance({}), nullptr);
  auto listed = ParseInstances(R"([
    {"00080018": {"vr": "UI", "Value": ["1.5"]}, "00200013": {"vr": "IS", "Value": [5]}},
    {"00080018": {"vr": "UI", "Value": ["1.1"]}, "00200013": {"vr": "IS", "Value": [1]}},
    {"00080018": {"vr": "UI", "Value": ["bad uid"]}},
    {"00080018": {"vr": "UI", "Value": ["1.3"]}, "00200013": {"vr": "IS", "Value": ["3"]}}])");
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_EQ(listed->size(), 3u);
  EXPECT_EQ(MiddleInstance(*listed)->sop_uid, "1.3");
}

}  // namespace
}  // namespace vpm::pacs

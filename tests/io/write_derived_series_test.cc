// The exported DICOM (write_derived_series.h, write_secondary_capture.h):
// read back by vpm's own reader with the volume's geometry and values, in
// the source's study with its patient, referencing the nearest source
// image; and valid against the IODs by dciodvfy (Debian's dicom3tools,
// installed by scripts/install-deps.sh; the test fails without it).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dctk.h>

#include "server/io/read_dicom_origin.h"
#include "server/io/read_dicom_series.h"
#include "server/io/write_derived_series.h"
#include "server/io/write_secondary_capture.h"

namespace vpm {
namespace {

// An oblique 9 x 7 x 5 grid (rotated 20 deg about z and 10 about x),
// anisotropic spacing, values over `range` HU.
Volume ObliqueVolume(float range) {
  VolumeGeometry g;
  g.dims = {9, 7, 5};
  g.spacing_mm = {0.8, 0.6, 2.5};
  g.origin_mm = {-30.5, 12.25, 101.0};
  const double a = glm::radians(20.0), b = glm::radians(10.0);
  const glm::dmat3 rz(std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a), 0, 0, 0, 1);
  const glm::dmat3 rx(1, 0, 0, 0, std::cos(b), std::sin(b), 0, -std::sin(b), std::cos(b));
  g.direction = rz * rx;
  std::vector<float> values(g.voxel_count());
  for (size_t n = 0; n < values.size(); ++n) {
    values[n] = -1000.0f + range * float(n % 97) / 96.0f;
  }
  return *Volume::Create(g, std::move(values));
}

DicomOrigin Origin(const std::string& modality) {
  DicomOrigin o;
  o.attributes = {{0x00080060, modality},        {0x00100010, "DOE^JANE"}, {0x00180015, "ABDOMEN"},
                  {0x00100020, "ID-42"},          {0x0020000D, "1.2.826.0.1.3680043.8.498.11"},
                  {0x00200011, "3"},              {0x00200052, "1.2.826.0.1.3680043.8.498.12"}};
  for (int k = 0; k < 5; ++k) {
    o.instances.push_back({.sop_class_uid = UID_CTImageStorage,
                           .sop_instance_uid = "1.2.826.0.1.3680043.8.498.13." + std::to_string(k),
                           .position_mm = glm::dvec3(0.0)});
  }
  return o;
}

std::filesystem::path WriteAll(const std::vector<DicomFileBytes>& files, const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("vpm-derived-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  for (const DicomFileBytes& f : files) {
    std::ofstream(dir / f.name, std::ios::binary) << f.bytes;
  }
  return dir;
}

// Lines of dciodvfy's report that start with "Error".
int DciodvfyErrors(const std::filesystem::path& file, std::string* report) {
  const std::string command = "dciodvfy '" + file.string() + "' 2>&1";
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return -1;
  char line[4096];
  int errors = 0;
  while (std::fgets(line, sizeof line, pipe) != nullptr) {
    *report += line;
    if (std::string(line).starts_with("Error")) ++errors;
  }
  const int rc = ::pclose(pipe);
  return WIFEXITED(rc) && WEXITSTATUS(rc) == 127 ? -1 : errors;
}

void ExpectRoundTrip(float range, double tolerance) {
  const Volume volume = ObliqueVolume(range);
  DicomOrigin origin = Origin("CT");
  for (int k = 0; k < 5; ++k) {
    origin.instances[k].position_mm =
        volume.geometry().PhysicalToWorld(glm::dvec3(0, 0, k * 2.5));
  }
  const DicomExportIds ids = MakeDicomExportIds(&origin);
  EXPECT_EQ(ids.study_uid, "1.2.826.0.1.3680043.8.498.11");
  EXPECT_EQ(ids.frame_of_reference_uid, "1.2.826.0.1.3680043.8.498.12");
  EXPECT_EQ(ids.derived_series_number, 1003);
  auto files = WriteDerivedSeries(volume, &origin, ids, {"vpm deformed", "a test"});
  ASSERT_TRUE(files.ok()) << files.status();
  ASSERT_EQ(files->size(), 5u);
  const auto dir = WriteAll(*files, std::to_string(int(range)));
  auto back = ReadDicomSeries(dir, {});
  ASSERT_TRUE(back.ok()) << back.status();
  const VolumeGeometry &a = volume.geometry(), &b = back->geometry();
  EXPECT_EQ(a.dims, b.dims);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(a.spacing_mm[c], b.spacing_mm[c], 1e-6);
    EXPECT_NEAR(a.origin_mm[c], b.origin_mm[c], 1e-6);
    for (int r = 0; r < 3; ++r) EXPECT_NEAR(a.direction[c][r], b.direction[c][r], 1e-6);
  }
  double worst = 0.0;
  for (int64_t n = 0; n < a.voxel_count(); ++n) {
    worst = std::max(worst, double(std::abs(volume.voxels()[n] - back->voxels()[n])));
  }
  EXPECT_LE(worst, tolerance) << "largest value difference";
  // Same study and patient, a new series, the nearest source image named.
  ASSERT_NE(back->dicom_origin(), nullptr);
  EXPECT_EQ(back->dicom_origin()->Get(0x0020000D), ids.study_uid);
  EXPECT_EQ(back->dicom_origin()->Get(0x00100010), "DOE^JANE");
  DcmFileFormat third;
  ASSERT_TRUE(third.loadFile((dir / "000003.dcm").c_str()).good());
  OFString value;
  third.getDataset()->findAndGetOFString(DCM_SeriesInstanceUID, value);
  EXPECT_EQ(std::string(value.c_str()), ids.derived_series_uid);
  third.getDataset()->findAndGetOFStringArray(DCM_ImageType, value);
  EXPECT_EQ(std::string(value.c_str()), "DERIVED\\SECONDARY\\AXIAL");
  DcmItem* reference = nullptr;
  ASSERT_TRUE(third.getDataset()->findAndGetSequenceItem(DCM_SourceImageSequence, reference).good());
  reference->findAndGetOFString(DCM_ReferencedSOPInstanceUID, value);
  EXPECT_EQ(std::string(value.c_str()), "1.2.826.0.1.3680043.8.498.13.2");
  std::string report;
  EXPECT_EQ(DciodvfyErrors(dir / "000003.dcm", &report), 0) << report;
  std::filesystem::remove_all(dir);
}

TEST(WriteDerivedSeries, ReadsBackWithTheGeometryAndHounsfieldValues) {
  ExpectRoundTrip(3000.0f, 0.5);  // fits int16: slope 1, values rounded
}

TEST(WriteDerivedSeries, ARangeOverInt16IsRescaled) {
  ExpectRoundTrip(200000.0f, 201000.0 / 65535.0);  // one stored step
}

TEST(WriteDerivedSeries, MrSourceGivesMrImagesAndOtherModalitiesAreRefused) {
  const Volume volume = ObliqueVolume(500.0f);
  DicomOrigin mr = Origin("MR");
  auto files = WriteDerivedSeries(volume, &mr, MakeDicomExportIds(&mr), {"d", "t"});
  ASSERT_TRUE(files.ok()) << files.status();
  const auto dir = WriteAll(*files, "mr");
  std::string report;
  EXPECT_EQ(DciodvfyErrors(dir / "000001.dcm", &report), 0) << report;
  EXPECT_NE(report.find("MRImage"), std::string::npos) << report;
  std::filesystem::remove_all(dir);
  DicomOrigin pet = Origin("PT");
  auto refused = WriteDerivedSeries(volume, &pet, MakeDicomExportIds(&pet), {"d", "t"});
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("PT"), std::string::npos);
}

TEST(WriteDerivedSeries, WithoutADicomSourceTheStudyIsNewAndThePatientEmpty) {
  const Volume volume = ObliqueVolume(500.0f);
  const DicomExportIds ids = MakeDicomExportIds(nullptr);
  EXPECT_FALSE(ids.study_uid.empty());
  EXPECT_NE(ids.study_uid, ids.frame_of_reference_uid);
  auto files = WriteDerivedSeries(volume, nullptr, ids, {"d", "t"});
  ASSERT_TRUE(files.ok()) << files.status();
  const auto dir = WriteAll(*files, "none");
  std::string report;
  EXPECT_EQ(DciodvfyErrors(dir / "000002.dcm", &report), 0) << report;
  std::filesystem::remove_all(dir);
}

// A description beyond ASCII (the user's, UTF-8) makes the series UTF-8:
// the source's Latin-1 name converted from its declared ISO_IR 100, or read
// as Latin-1 where the source declares nothing; an ASCII description keeps
// the source's set and bytes as they were.
TEST(WriteDerivedSeries, ADescriptionBeyondAsciiMakesTheSeriesUtf8) {
  const Volume volume = ObliqueVolume(500.0f);
  const std::string described = "Niere links \xe2\x80\x93 Plan";  // an en dash
  const std::string name_utf8 = "M\xc3\xbcller^J\xc3\xb6rg";
  for (const bool declared : {true, false}) {
    DicomOrigin origin = Origin("CT");
    origin.attributes[1].second = "M\xfcller^J\xf6rg";  // PatientName, Latin-1
    if (declared) origin.attributes.insert(origin.attributes.begin(), {0x00080005, "ISO_IR 100"});
    for (const std::string& description : {described, std::string("ascii plan")}) {
      auto files =
          WriteDerivedSeries(volume, &origin, MakeDicomExportIds(&origin), {description, "t"});
      ASSERT_TRUE(files.ok()) << files.status();
      const auto dir = WriteAll(*files, declared ? "utf8-declared" : "utf8-undeclared");
      DcmFileFormat first;
      ASSERT_TRUE(first.loadFile((dir / "000001.dcm").c_str()).good());
      OFString charset, name, series;
      first.getDataset()->findAndGetOFStringArray(DCM_SpecificCharacterSet, charset);
      first.getDataset()->findAndGetOFStringArray(DCM_PatientName, name);
      first.getDataset()->findAndGetOFStringArray(DCM_SeriesDescription, series);
      if (description == described) {
        EXPECT_EQ(std::string(charset.c_str()), "ISO_IR 192") << declared;
        EXPECT_EQ(std::string(name.c_str()), name_utf8) << declared;
        EXPECT_EQ(std::string(series.c_str()), described);
        std::string report;
        EXPECT_EQ(DciodvfyErrors(dir / "000001.dcm", &report), 0) << report;
      } else {
        EXPECT_EQ(std::string(charset.c_str()), declared ? "ISO_IR 100" : "") << declared;
        EXPECT_EQ(std::string(name.c_str()), "M\xfcller^J\xf6rg") << declared;
      }
      std::filesystem::remove_all(dir);
    }
  }
}

TEST(WriteSecondaryCapture, HoldsTheFrameAsRgbInTheStudy) {
  const int w = 6, h = 4;
  std::vector<uint8_t> rgba(w * h * 4);
  for (size_t n = 0; n < rgba.size(); ++n) rgba[n] = uint8_t(n * 7);
  DicomOrigin origin = Origin("CT");
  const DicomExportIds ids = MakeDicomExportIds(&origin);
  auto bytes = WriteSecondaryCapture(rgba, w, h, &origin, ids, "vpm 3D view");
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  const auto dir = WriteAll({{"sc.dcm", *bytes}}, "sc");
  DcmFileFormat file;
  ASSERT_TRUE(file.loadFile((dir / "sc.dcm").c_str()).good());
  DcmDataset& ds = *file.getDataset();
  OFString value;
  ds.findAndGetOFString(DCM_StudyInstanceUID, value);
  EXPECT_EQ(std::string(value.c_str()), ids.study_uid);
  ds.findAndGetOFString(DCM_SeriesInstanceUID, value);
  EXPECT_EQ(std::string(value.c_str()), ids.capture_series_uid);
  const Uint8* pixels = nullptr;
  unsigned long count = 0;
  ASSERT_TRUE(ds.findAndGetUint8Array(DCM_PixelData, pixels, &count).good());
  ASSERT_EQ(count, size_t(w * h * 3));
  for (int p = 0; p < w * h; ++p) {
    for (int c = 0; c < 3; ++c) ASSERT_EQ(pixels[p * 3 + c], rgba[p * 4 + c]) << p;
  }
  std::string report;
  EXPECT_EQ(DciodvfyErrors(dir / "sc.dcm", &report), 0) << report;
  std::filesystem::remove_all(dir);
  EXPECT_EQ(WriteSecondaryCapture(rgba, w + 1, h, &origin, ids, "x").status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

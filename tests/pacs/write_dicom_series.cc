// Writes a volume (any source ReadVolume takes, e.g. the kidney CT's NIfTI)
// as a DICOM CT series, one file per slice, for the PACS tests; or, with
// --structured-report, one Basic Text SR object (a non-image series).
//
//   vpm_test_write_dicom_series SOURCE OUT_DIR --study-uid U --series-uid U
//       --patient-name N --patient-id ID --birth-date YYYYMMDD --study-date YYYYMMDD
//       [--series-number N] [--description TEXT]
//   vpm_test_write_dicom_series --structured-report OUT_DIR --study-uid U --series-uid U ...
//
// Slice k lies at origin + k * spacing_z * normal (ImagePositionPatient),
// ImageOrientationPatient = the volume's first two direction columns,
// PixelSpacing = (spacing_y, spacing_x); values are written as int16 with
// slope 1 and intercept 0, so that a reader gets the source's values back
// exactly (the source must hold integers in int16's range).
#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcuid.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "server/common/valid_utf8.h"
#include "server/io/read_volume.h"

namespace {

// A DS value in at most 16 characters.
std::string Ds(double v) {
  for (int precision = 12; precision > 1; --precision) {
    char text[64];
    std::snprintf(text, sizeof(text), "%.*g", precision, v);
    if (std::string(text).size() <= 16) return text;
  }
  return "0";
}

std::string Ds3(double a, double b, double c) { return Ds(a) + "\\" + Ds(b) + "\\" + Ds(c); }

void PutCommon(DcmDataset& ds, std::map<std::string, std::string>& flags) {
  // A name beyond ASCII (the flags are UTF-8) is declared as such.
  const std::string& name = flags["--patient-name"];
  if (!vpm::IsAscii(name)) {
    ds.putAndInsertString(DCM_SpecificCharacterSet, "ISO_IR 192");
  }
  ds.putAndInsertString(DCM_StudyInstanceUID, flags["--study-uid"].c_str());
  ds.putAndInsertString(DCM_SeriesInstanceUID, flags["--series-uid"].c_str());
  ds.putAndInsertString(DCM_PatientName, flags["--patient-name"].c_str());
  ds.putAndInsertString(DCM_PatientID, flags["--patient-id"].c_str());
  ds.putAndInsertString(DCM_PatientBirthDate, flags["--birth-date"].c_str());
  ds.putAndInsertString(DCM_PatientSex, "O");
  ds.putAndInsertString(DCM_StudyDate, flags["--study-date"].c_str());
  ds.putAndInsertString(DCM_StudyTime, "120000");
  ds.putAndInsertString(DCM_AccessionNumber, flags["--accession"].c_str());
  ds.putAndInsertString(DCM_StudyID, "1");
  ds.putAndInsertString(DCM_ReferringPhysicianName, "");
  ds.putAndInsertString(DCM_StudyDescription, "vpm PACS test study");
  ds.putAndInsertString(DCM_SeriesDescription, flags["--description"].c_str());
  ds.putAndInsertString(DCM_SeriesNumber, flags["--series-number"].c_str());
}

int WriteReport(const std::filesystem::path& out, std::map<std::string, std::string>& flags) {
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  PutCommon(ds, flags);
  ds.putAndInsertString(DCM_SOPClassUID, UID_BasicTextSRStorage);
  ds.putAndInsertString(DCM_SOPInstanceUID, (flags["--series-uid"] + ".1").c_str());
  ds.putAndInsertString(DCM_Modality, "SR");
  ds.putAndInsertString(DCM_InstanceNumber, "1");
  ds.putAndInsertString(DCM_ValueType, "CONTAINER");
  ds.putAndInsertString(DCM_ContinuityOfContent, "SEPARATE");
  ds.putAndInsertString(DCM_CompletionFlag, "COMPLETE");
  ds.putAndInsertString(DCM_VerificationFlag, "UNVERIFIED");
  DcmItem* code_item = nullptr;
  if (ds.findOrCreateSequenceItem(DCM_ConceptNameCodeSequence, code_item, -2).good()) {
    code_item->putAndInsertString(DCM_CodeValue, "11528-7");
    code_item->putAndInsertString(DCM_CodingSchemeDesignator, "LN");
    code_item->putAndInsertString(DCM_CodeMeaning, "Radiology Report");
  }
  std::filesystem::create_directories(out);
  if (file.saveFile((out / "report.dcm").c_str(), EXS_LittleEndianExplicit).bad()) {
    std::fprintf(stderr, "cannot write the report\n");
    return 1;
  }
  return 0;
}

// Slice k's CT image, image plane and pixel modules (int16, rescale 1/0)
// on the volume's grid g.
void PutSlice(DcmDataset& ds, std::map<std::string, std::string>& flags,
              const vpm::VolumeGeometry& g, int64_t k, const char* frame_uid) {
  const glm::dvec3 row = g.direction[0], column = g.direction[1], normal = g.direction[2];
  PutCommon(ds, flags);
  ds.putAndInsertString(DCM_SOPClassUID, UID_CTImageStorage);
  ds.putAndInsertString(DCM_SOPInstanceUID,
                        (flags["--series-uid"] + "." + std::to_string(k + 1)).c_str());
  ds.putAndInsertString(DCM_FrameOfReferenceUID, frame_uid);
  ds.putAndInsertString(DCM_Modality, "CT");
  ds.putAndInsertString(DCM_BodyPartExamined, "ABDOMEN");
  ds.putAndInsertString(DCM_ImageType, "ORIGINAL\\PRIMARY\\AXIAL");
  ds.putAndInsertString(DCM_InstanceNumber, std::to_string(k + 1).c_str());
  const glm::dvec3 p = g.origin_mm + normal * (static_cast<double>(k) * g.spacing_mm.z);
  ds.putAndInsertString(DCM_ImagePositionPatient, Ds3(p.x, p.y, p.z).c_str());
  ds.putAndInsertString(
      DCM_ImageOrientationPatient,
      (Ds3(row.x, row.y, row.z) + "\\" + Ds3(column.x, column.y, column.z)).c_str());
  ds.putAndInsertString(DCM_PixelSpacing, (Ds(g.spacing_mm.y) + "\\" + Ds(g.spacing_mm.x)).c_str());
  ds.putAndInsertString(DCM_SliceThickness, Ds(g.spacing_mm.z).c_str());
  ds.putAndInsertUint16(DCM_Rows, static_cast<Uint16>(g.dims[1]));
  ds.putAndInsertUint16(DCM_Columns, static_cast<Uint16>(g.dims[0]));
  ds.putAndInsertUint16(DCM_SamplesPerPixel, 1);
  ds.putAndInsertString(DCM_PhotometricInterpretation, "MONOCHROME2");
  ds.putAndInsertUint16(DCM_BitsAllocated, 16);
  ds.putAndInsertUint16(DCM_BitsStored, 16);
  ds.putAndInsertUint16(DCM_HighBit, 15);
  ds.putAndInsertUint16(DCM_PixelRepresentation, 1);
  ds.putAndInsertString(DCM_RescaleIntercept, "0");
  ds.putAndInsertString(DCM_RescaleSlope, "1");
}

// Slice k's voxels as int16 pixels, x fastest; false (with a message) when
// one is not an integer in int16's range.
bool SlicePixels(const vpm::Volume& volume, int64_t k, std::vector<Uint16>& pixels) {
  const auto [nx, ny, nz] = volume.geometry().dims;
  for (int64_t j = 0; j < ny; ++j) {
    for (int64_t i = 0; i < nx; ++i) {
      const float v = volume.At(i, j, k);
      if (v != std::round(v) || v < -32768 || v > 32767) {
        std::fprintf(stderr, "voxel (%lld,%lld,%lld) = %g is not an int16\n",
                     static_cast<long long>(i), static_cast<long long>(j),
                     static_cast<long long>(k), v);
        return false;
      }
      pixels[static_cast<size_t>(i + nx * j)] = static_cast<Uint16>(static_cast<int16_t>(v));
    }
  }
  return true;
}

// The volume at `source` as one CT file per slice in `out`.
int WriteSeries(const std::string& source, const std::filesystem::path& out,
                std::map<std::string, std::string>& flags) {
  auto volume = vpm::ReadVolume(source, vpm::VolumeLimits{});
  if (!volume.ok()) {
    std::fprintf(stderr, "%s\n", std::string(volume.status().message()).c_str());
    return 1;
  }
  std::filesystem::create_directories(out);
  const auto& g = volume->geometry();
  const auto [nx, ny, nz] = g.dims;
  char frame_uid[100];
  dcmGenerateUniqueIdentifier(frame_uid, SITE_INSTANCE_UID_ROOT);
  std::vector<Uint16> pixels(static_cast<size_t>(nx * ny));
  for (int64_t k = 0; k < nz; ++k) {
    DcmFileFormat file;
    DcmDataset& ds = *file.getDataset();
    PutSlice(ds, flags, g, k, frame_uid);
    if (!SlicePixels(*volume, k, pixels)) return 1;
    ds.putAndInsertUint16Array(DCM_PixelData, pixels.data(), pixels.size());
    char name[32];
    std::snprintf(name, sizeof(name), "slice%04lld.dcm", static_cast<long long>(k + 1));
    if (file.saveFile((out / name).c_str(), EXS_LittleEndianExplicit).bad()) {
      std::fprintf(stderr, "cannot write %s\n", name);
      return 1;
    }
  }
  std::printf("%lld slices of %lldx%lld\n", static_cast<long long>(nz), static_cast<long long>(nx),
              static_cast<long long>(ny));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> positional;
  std::map<std::string, std::string> flags = {
      {"--study-uid", ""},      {"--series-uid", ""},    {"--patient-name", ""},
      {"--patient-id", ""},     {"--birth-date", ""},    {"--study-date", ""},
      {"--series-number", "1"}, {"--description", "CT"}, {"--accession", "ACC1"}};
  bool report = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--structured-report") {
      report = true;
    } else if (flags.contains(arg) && i + 1 < argc) {
      flags[arg] = argv[++i];
    } else {
      positional.push_back(arg);
    }
  }
  if (flags["--study-uid"].empty() || flags["--series-uid"].empty() ||
      positional.size() != (report ? 1u : 2u)) {
    std::fprintf(stderr, "usage: see the comment at the top of write_dicom_series.cc\n");
    return 2;
  }
  if (report) return WriteReport(positional[0], flags);
  return WriteSeries(positional[0], positional[1], flags);
}

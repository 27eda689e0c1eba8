// Writes small DICOM slices with DCMTK, for tests and fuzz seed corpora.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <dcmtk/config/osconfig.h>  // must come first among DCMTK headers
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcrleerg.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <dcmtk/dcmjpeg/djencode.h>
#include <dcmtk/dcmjpls/djencode.h>

#include <glm/glm.hpp>

namespace vpm::testing {

struct DicomSliceSpec {
  std::string series_uid = "1.2.826.0.1.3680043.8.498.1";
  std::string sop_class_uid = UID_CTImageStorage;
  std::string modality = "CT";
  std::string series_description;  // empty: not written
  std::string image_type;          // e.g. "ORIGINAL\\PRIMARY\\LOCALIZER"; empty: not written
  int series_number = 0;           // 0: not written
  int instance_number = 0;         // 0: not written
  std::string manufacturer;        // empty: not written
  std::string gantry_tilt_deg;     // GantryDetectorTilt as text; empty: not written
  int rows = 3;
  int columns = 4;
  std::array<double, 2> pixel_spacing_mm{0.75, 0.5};  // between rows, between columns
  std::array<double, 6> orientation{1, 0, 0, 0, 1, 0};
  glm::dvec3 position_mm{0.0};
  double slope = 1.0;
  double intercept = -1024.0;
  int bits_allocated = 16;
  int bits_stored = 16;
  bool is_signed = true;
  int samples_per_pixel = 1;
  std::string number_of_frames;     // empty: not written
  double slice_thickness_mm = 0.0;  // 0: not written
  bool with_position = true;
  bool with_pixel_data = true;
  E_TransferSyntax transfer_syntax = EXS_LittleEndianExplicit;
  std::vector<int32_t> stored;  // rows * columns samples; empty: n % 100
  // More attributes as text (EchoNumbers, TemporalPositionIdentifier, ...).
  std::vector<std::pair<DcmTagKey, std::string>> more;
};

inline std::string DicomNumbers(std::initializer_list<double> values) {
  std::string out;
  for (double v : values) {
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.6g", v);
    if (!out.empty()) out += "\\";
    out += buffer;
  }
  return out;
}

inline void PutPixels(DcmDataset& ds, const DicomSliceSpec& s) {
  const size_t count = static_cast<size_t>(s.rows) * s.columns * s.samples_per_pixel;
  std::vector<int32_t> stored = s.stored;
  if (stored.empty()) {
    for (size_t n = 0; n < count; ++n) stored.push_back(static_cast<int32_t>(n % 100));
  }
  if (s.bits_allocated == 8) {
    std::vector<Uint8> data(count);
    for (size_t n = 0; n < count; ++n) data[n] = static_cast<Uint8>(stored[n]);
    ds.putAndInsertUint8Array(DCM_PixelData, data.data(), count);
  } else {
    std::vector<Uint16> data(count);
    for (size_t n = 0; n < count; ++n) data[n] = static_cast<Uint16>(stored[n]);
    ds.putAndInsertUint16Array(DCM_PixelData, data.data(), count);
  }
}

// Fills a CT image dataset from `s`.
inline void FillDicomSlice(DcmDataset& ds, const DicomSliceSpec& s) {
  char uid[100];
  ds.putAndInsertString(DCM_SOPClassUID, s.sop_class_uid.c_str());
  ds.putAndInsertString(DCM_SOPInstanceUID,
                        dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT));
  ds.putAndInsertString(DCM_StudyInstanceUID, "1.2.826.0.1.3680043.8.498.9");
  ds.putAndInsertString(DCM_SeriesInstanceUID, s.series_uid.c_str());
  ds.putAndInsertString(DCM_Modality, s.modality.c_str());
  if (!s.series_description.empty()) {
    ds.putAndInsertString(DCM_SeriesDescription, s.series_description.c_str());
  }
  if (!s.image_type.empty()) ds.putAndInsertString(DCM_ImageType, s.image_type.c_str());
  if (s.instance_number != 0) {
    ds.putAndInsertString(DCM_InstanceNumber, std::to_string(s.instance_number).c_str());
  }
  if (!s.manufacturer.empty()) ds.putAndInsertString(DCM_Manufacturer, s.manufacturer.c_str());
  if (!s.gantry_tilt_deg.empty()) {
    ds.putAndInsertString(DCM_GantryDetectorTilt, s.gantry_tilt_deg.c_str());
  }
  if (s.series_number != 0) {
    ds.putAndInsertString(DCM_SeriesNumber, std::to_string(s.series_number).c_str());
  }
  ds.putAndInsertUint16(DCM_Rows, static_cast<Uint16>(s.rows));
  ds.putAndInsertUint16(DCM_Columns, static_cast<Uint16>(s.columns));
  ds.putAndInsertUint16(DCM_SamplesPerPixel, static_cast<Uint16>(s.samples_per_pixel));
  ds.putAndInsertString(DCM_PhotometricInterpretation,
                        s.samples_per_pixel == 1 ? "MONOCHROME2" : "RGB");
  if (s.samples_per_pixel > 1) ds.putAndInsertUint16(DCM_PlanarConfiguration, 0);
  ds.putAndInsertUint16(DCM_BitsAllocated, static_cast<Uint16>(s.bits_allocated));
  ds.putAndInsertUint16(DCM_BitsStored, static_cast<Uint16>(s.bits_stored));
  ds.putAndInsertUint16(DCM_HighBit, static_cast<Uint16>(s.bits_stored - 1));
  ds.putAndInsertUint16(DCM_PixelRepresentation, s.is_signed ? 1 : 0);
  ds.putAndInsertString(DCM_PixelSpacing,
                        DicomNumbers({s.pixel_spacing_mm[0], s.pixel_spacing_mm[1]}).c_str());
  const auto& o = s.orientation;
  ds.putAndInsertString(DCM_ImageOrientationPatient,
                        DicomNumbers({o[0], o[1], o[2], o[3], o[4], o[5]}).c_str());
  if (s.with_position) {
    const glm::dvec3& p = s.position_mm;
    ds.putAndInsertString(DCM_ImagePositionPatient, DicomNumbers({p.x, p.y, p.z}).c_str());
  }
  if (s.slice_thickness_mm > 0) {
    ds.putAndInsertString(DCM_SliceThickness, DicomNumbers({s.slice_thickness_mm}).c_str());
  }
  if (!s.number_of_frames.empty()) {
    ds.putAndInsertString(DCM_NumberOfFrames, s.number_of_frames.c_str());
  }
  ds.putAndInsertString(DCM_RescaleSlope, DicomNumbers({s.slope}).c_str());
  ds.putAndInsertString(DCM_RescaleIntercept, DicomNumbers({s.intercept}).c_str());
  for (const auto& [tag, value] : s.more) ds.putAndInsertString(tag, value.c_str());
  if (s.with_pixel_data) PutPixels(ds, s);
}

// Writes `s` as a DICOM Part 10 file; false on failure.
// One frame of an Enhanced CT (FillEnhancedCt).
struct EnhancedFrame {
  glm::dvec3 position_mm{0.0};
  double intercept = -1024.0;  // written per frame when `per_frame_rescale`
};

// An Enhanced CT dataset of `frames` without PixelData (the caller adds it,
// native or encapsulated; `s` gives rows and columns): PixelSpacing,
// SliceThickness and ImageOrientationPatient in the shared functional
// groups and ImagePositionPatient (and, when asked, the rescale) per frame.
// Top-level geometry attributes are absent, as in the standard's enhanced
// IODs. NumberOfFrames is `number_of_frames`, else the frame count. False
// when DCMTK refuses an item.
inline bool FillEnhancedCt(DcmDataset& ds, DicomSliceSpec& s,
                           const std::vector<EnhancedFrame>& frames, bool per_frame_rescale,
                           const std::string& number_of_frames = "") {
  s.sop_class_uid = UID_EnhancedCTImageStorage;
  s.with_position = false;
  s.with_pixel_data = false;
  FillDicomSlice(ds, s);
  ds.findAndDeleteElement(DCM_PixelSpacing);
  ds.findAndDeleteElement(DCM_ImageOrientationPatient);
  ds.findAndDeleteElement(DCM_RescaleIntercept);
  ds.findAndDeleteElement(DCM_RescaleSlope);
  ds.putAndInsertString(DCM_NumberOfFrames, number_of_frames.empty()
                                                ? std::to_string(frames.size()).c_str()
                                                : number_of_frames.c_str());
  DcmItem *shared = nullptr, *measures = nullptr, *orientation = nullptr, *transform = nullptr;
  if (ds.findOrCreateSequenceItem(DCM_SharedFunctionalGroupsSequence, shared, -2).bad() ||
      shared->findOrCreateSequenceItem(DCM_PixelMeasuresSequence, measures, -2).bad() ||
      shared->findOrCreateSequenceItem(DCM_PlaneOrientationSequence, orientation, -2).bad()) {
    return false;
  }
  measures->putAndInsertString(DCM_PixelSpacing, "0.75\\0.5");
  measures->putAndInsertString(DCM_SliceThickness, "2");
  orientation->putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0\\1\\0");
  if (!per_frame_rescale) {
    if (shared->findOrCreateSequenceItem(DCM_PixelValueTransformationSequence, transform, -2)
            .bad()) {
      return false;
    }
    transform->putAndInsertString(DCM_RescaleSlope, "1");
    transform->putAndInsertString(DCM_RescaleIntercept, "-1024");
  }
  for (const EnhancedFrame& frame : frames) {
    DcmItem *group = nullptr, *position = nullptr;
    if (ds.findOrCreateSequenceItem(DCM_PerFrameFunctionalGroupsSequence, group, -2).bad() ||
        group->findOrCreateSequenceItem(DCM_PlanePositionSequence, position, -2).bad()) {
      return false;
    }
    const glm::dvec3& p = frame.position_mm;
    position->putAndInsertString(DCM_ImagePositionPatient, DicomNumbers({p.x, p.y, p.z}).c_str());
    if (per_frame_rescale) {
      if (group->findOrCreateSequenceItem(DCM_PixelValueTransformationSequence, transform, -2)
              .bad()) {
        return false;
      }
      transform->putAndInsertString(DCM_RescaleSlope, "1");
      transform->putAndInsertString(DCM_RescaleIntercept, DicomNumbers({frame.intercept}).c_str());
    }
  }
  return true;
}

inline bool WriteDicomSlice(const std::filesystem::path& path, const DicomSliceSpec& s) {
  static const bool registered = [] {
    DcmRLEEncoderRegistration::registerCodecs();
    DJEncoderRegistration::registerCodecs();
    DJLSEncoderRegistration::registerCodecs();
    return true;
  }();
  (void)registered;
  DcmFileFormat file;
  DcmDataset& ds = *file.getDataset();
  FillDicomSlice(ds, s);
  if (DcmXfer(s.transfer_syntax).isEncapsulated() &&
      ds.chooseRepresentation(s.transfer_syntax, nullptr).bad()) {
    return false;
  }
  return file.saveFile(path.c_str(), s.transfer_syntax).good();
}

}  // namespace vpm::testing

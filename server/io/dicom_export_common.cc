#include "server/io/dicom_export_common.h"

#include <algorithm>
#include <ctime>
#include <iterator>

#include <dcmtk/dcmdata/dcostrmb.h>
#include <dcmtk/dcmdata/dctk.h>

#include "server/common/valid_utf8.h"
#include "server/io/dicom_text.h"

namespace vpm {
namespace {

std::string NewUid() {
  char uid[100];
  dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT);
  return uid;
}

// The export's own text (a description the user typed) is UTF-8. Where it
// is not ASCII the dataset is declared ISO_IR 192 and the source's copied
// text made UTF-8 too: converted from the set the source declares (DCMTK),
// or, none declared, read as Latin-1 where it is not UTF-8 (ValidUtf8).
// Otherwise the source's set is kept as copied.
Status DeclareUtf8ForText(DcmDataset& ds, const DicomOrigin* origin, const std::string& text) {
  if (IsAscii(text)) return absl::OkStatus();
  ConvertDicomTextToUtf8(ds);
  OFString charset;
  if (ds.findAndGetOFStringArray(DCM_SpecificCharacterSet, charset).good() && !charset.empty() &&
      charset != "ISO_IR 192") {
    return absl::InvalidArgumentError(
        StrCat("series_description: not ASCII, and the source's character set '",
               std::string_view(charset.c_str(), std::min<size_t>(charset.size(), 64)),
               "' cannot be converted to UTF-8 to hold it; use ASCII"));
  }
  if (origin != nullptr && charset.empty()) {  // none declared: copied as stored
    for (const auto& [tag, value] : origin->attributes) {
      const DcmTagKey key(static_cast<Uint16>(tag >> 16), static_cast<Uint16>(tag & 0xffff));
      if (!IsAscii(value) && ds.tagExists(key)) {
        RETURN_IF_ERROR(PutDicomString(ds, key, ValidUtf8(value)));
      }
    }
  }
  return PutDicomString(ds, DCM_SpecificCharacterSet, "ISO_IR 192");
}

}  // namespace

Status PutDicomString(DcmDataset& ds, const DcmTagKey& key, const std::string& value) {
  const OFCondition c = ds.putAndInsertOFStringArray(key, OFString(value.c_str(), value.size()));
  if (c.bad()) {
    return absl::InternalError(StrCat("cannot set ", DcmTag(key).getTagName(), ": ", c.text()));
  }
  return absl::OkStatus();
}

DicomExportIds MakeDicomExportIds(const DicomOrigin* origin) {
  DicomExportIds ids;
  const auto from_origin = [&](const DcmTagKey& key) {
    return origin ? origin->Get((uint32_t{key.getGroup()} << 16) | key.getElement())
                  : std::string();
  };
  ids.study_uid = from_origin(DCM_StudyInstanceUID);
  if (ids.study_uid.empty()) ids.study_uid = NewUid();
  ids.frame_of_reference_uid = from_origin(DCM_FrameOfReferenceUID);
  if (ids.frame_of_reference_uid.empty()) ids.frame_of_reference_uid = NewUid();
  ids.derived_series_uid = NewUid();
  ids.capture_series_uid = NewUid();
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  localtime_r(&now, &local);
  char text[16];
  std::strftime(text, sizeof text, "%Y%m%d", &local);
  ids.date = text;
  std::strftime(text, sizeof text, "%H%M%S", &local);
  ids.time = text;
  const std::string number = from_origin(DCM_SeriesNumber);
  ids.derived_series_number = 1000 + (number.empty() ? 0 : std::atoll(number.c_str()));
  return ids;
}

Status PutCommonModules(DcmDataset& ds, const DicomOrigin* origin, const DicomExportIds& ids,
                        bool image_plane, const char* sop_class_uid, const std::string& modality,
                        const std::string& series_uid, int64_t series_number,
                        const std::string& series_description, int64_t number) {
  // Type 2 attributes of the patient, study and frame-of-reference modules:
  // present, empty when the source has no value (or there is no source).
  const DcmTagKey type2[] = {DCM_PatientName,       DCM_PatientID,   DCM_PatientBirthDate,
                             DCM_PatientSex,        DCM_StudyDate,   DCM_StudyTime,
                             DCM_ReferringPhysicianName, DCM_StudyID, DCM_AccessionNumber};
  for (const DcmTagKey& key : type2) RETURN_IF_ERROR(PutDicomString(ds, key, ""));
  // Only images placed in the patient carry these.
  const DcmTagKey placed[] = {DCM_FrameOfReferenceUID, DCM_PositionReferenceIndicator,
                              DCM_ScanningSequence,    DCM_SequenceVariant,
                              DCM_ScanOptions,         DCM_MRAcquisitionType,
                              DCM_RepetitionTime,      DCM_EchoTime,
                              DCM_EchoTrainLength,     DCM_MagneticFieldStrength};
  if (image_plane) RETURN_IF_ERROR(PutDicomString(ds, DCM_PositionReferenceIndicator, ""));
  if (origin != nullptr) {
    for (const auto& [tag, value] : origin->attributes) {
      const DcmTagKey key(static_cast<Uint16>(tag >> 16), static_cast<Uint16>(tag & 0xffff));
      if (key == DCM_Modality || key == DCM_SeriesNumber) continue;  // the export's own
      if (!image_plane && std::find(std::begin(placed), std::end(placed), key) != std::end(placed))
        continue;
      RETURN_IF_ERROR(PutDicomString(ds, key, value));
    }
  }
  // Laterality (type 2C in the general series) belongs to paired body
  // parts: copied when the source has it, empty (unknown) when the body part
  // is unknown, absent otherwise.
  const auto source_has = [&](const DcmTagKey& key) {
    return origin != nullptr &&
           !origin->Get((uint32_t{key.getGroup()} << 16) | key.getElement()).empty();
  };
  if (!source_has(DCM_BodyPartExamined) && !source_has(DCM_Laterality)) {
    RETURN_IF_ERROR(PutDicomString(ds, DCM_Laterality, ""));
  }
  RETURN_IF_ERROR(PutDicomString(ds, DCM_StudyInstanceUID, ids.study_uid));
  if (image_plane) {
    RETURN_IF_ERROR(PutDicomString(ds, DCM_FrameOfReferenceUID, ids.frame_of_reference_uid));
  }
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SOPClassUID, sop_class_uid));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SOPInstanceUID, NewUid()));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_InstanceCreationDate, ids.date));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_InstanceCreationTime, ids.time));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ContentDate, ids.date));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_ContentTime, ids.time));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SeriesDate, ids.date));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SeriesTime, ids.time));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_Manufacturer, "vpm"));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_Modality, modality));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SeriesInstanceUID, series_uid));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SeriesNumber, std::to_string(series_number)));
  RETURN_IF_ERROR(DeclareUtf8ForText(ds, origin, series_description));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_SeriesDescription, series_description));
  RETURN_IF_ERROR(PutDicomString(ds, DCM_InstanceNumber, std::to_string(number)));
  return absl::OkStatus();
}

void PutImagePixelModule(DcmDataset& ds, int samples, int64_t rows, int64_t columns, int bits,
                         bool is_signed) {
  ds.putAndInsertUint16(DCM_SamplesPerPixel, static_cast<Uint16>(samples));
  ds.putAndInsertString(DCM_PhotometricInterpretation, samples == 3 ? "RGB" : "MONOCHROME2");
  if (samples == 3) ds.putAndInsertUint16(DCM_PlanarConfiguration, 0);
  ds.putAndInsertUint16(DCM_Rows, static_cast<Uint16>(rows));
  ds.putAndInsertUint16(DCM_Columns, static_cast<Uint16>(columns));
  ds.putAndInsertUint16(DCM_BitsAllocated, static_cast<Uint16>(bits));
  ds.putAndInsertUint16(DCM_BitsStored, static_cast<Uint16>(bits));
  ds.putAndInsertUint16(DCM_HighBit, static_cast<Uint16>(bits - 1));
  ds.putAndInsertUint16(DCM_PixelRepresentation, is_signed ? 1 : 0);
}

Result<std::string> Part10Bytes(DcmFileFormat& file) {
  OFCondition c = file.validateMetaInfo(EXS_LittleEndianExplicit);
  if (c.bad()) return absl::InternalError(StrCat("DICOM meta header: ", c.text()));
  file.transferInit();
  const Uint32 length = file.calcElementLength(EXS_LittleEndianExplicit, EET_ExplicitLength);
  std::string bytes(size_t{length} + 4096, '\0');  // preamble, prefix, meta group lengths
  DcmOutputBufferStream out(bytes.data(), static_cast<offile_off_t>(bytes.size()));
  c = file.write(out, EXS_LittleEndianExplicit, EET_ExplicitLength, nullptr);
  file.transferEnd();
  if (c.bad() || c == EC_StreamNotifyClient) {
    return absl::InternalError(StrCat("cannot encode a DICOM file: ", c.text()));
  }
  void* buffer = nullptr;
  offile_off_t written = 0;
  out.flushBuffer(buffer, written);
  bytes.resize(static_cast<size_t>(written));
  return bytes;
}

}  // namespace vpm

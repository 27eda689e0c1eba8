#include "server/io/read_dicom_origin.h"

#include <dcmtk/dcmdata/dctk.h>

#include "server/common/prefix_status.h"

namespace vpm {
namespace {

uint32_t TagKey(const DcmTagKey& key) {
  return (uint32_t{key.getGroup()} << 16) | key.getElement();
}

// Every value of `key` in `ds`, joined by '\' as DICOM stores them; "" when absent.
std::string AllValues(DcmItem& ds, const DcmTagKey& key) {
  OFString value;
  if (ds.findAndGetOFStringArray(key, value).bad()) return {};
  return std::string(value.c_str(), value.size());
}

}  // namespace

const std::vector<uint32_t>& DicomOriginTags() {
  static const std::vector<uint32_t> tags = [] {
    const DcmTagKey keys[] = {
        DCM_SpecificCharacterSet, DCM_StudyDate, DCM_StudyTime, DCM_AccessionNumber,
        DCM_Modality, DCM_ReferringPhysicianName, DCM_StudyDescription, DCM_PatientName,
        DCM_PatientID, DCM_PatientBirthDate, DCM_PatientSex, DCM_PatientAge,
        DCM_BodyPartExamined, DCM_Laterality, DCM_ScanningSequence, DCM_SequenceVariant, DCM_ScanOptions,
        DCM_MRAcquisitionType, DCM_RepetitionTime, DCM_EchoTime, DCM_EchoTrainLength,
        DCM_MagneticFieldStrength, DCM_PatientPosition, DCM_StudyInstanceUID,
        DCM_SeriesNumber, DCM_StudyID, DCM_FrameOfReferenceUID, DCM_PositionReferenceIndicator,
    };
    std::vector<uint32_t> out;
    for (const DcmTagKey& key : keys) out.push_back(TagKey(key));
    return out;
  }();
  return tags;
}

Result<DicomOrigin> ReadDicomOrigin(const std::vector<std::filesystem::path>& files) {
  DicomOrigin origin;
  for (size_t n = 0; n < files.size(); ++n) {
    DcmFileFormat file;
    // Values over 4 KiB (the pixel data) stay on disk, unread.
    const OFCondition read =
        file.loadFile(files[n].c_str(), EXS_Unknown, EGL_noChange, 4096, ERM_autoDetect);
    if (read.bad()) {
      return absl::InvalidArgumentError(
          StrCat(files[n].filename().string(), ": not a readable DICOM file (", read.text(), ")"));
    }
    DcmDataset& ds = *file.getDataset();
    if (n == 0) {
      for (const uint32_t tag : DicomOriginTags()) {
        const DcmTagKey key(static_cast<Uint16>(tag >> 16), static_cast<Uint16>(tag & 0xffff));
        if (!ds.tagExists(key)) continue;
        origin.attributes.emplace_back(tag, AllValues(ds, key));
      }
    }
    DicomSourceInstance instance{.sop_class_uid = AllValues(ds, DCM_SOPClassUID),
                                 .sop_instance_uid = AllValues(ds, DCM_SOPInstanceUID)};
    for (int c = 0; c < 3; ++c) {
      Float64 v = 0.0;
      if (ds.findAndGetFloat64(DCM_ImagePositionPatient, v, c).good()) instance.position_mm[c] = v;
    }
    origin.instances.push_back(std::move(instance));
  }
  return origin;
}

}  // namespace vpm

// What the writers of exported DICOM (write_derived_series.h,
// write_secondary_capture.h) share: the identity of one export, the
// attributes every exported instance copies from its source series, and a
// dataset as Part 10 bytes.
#pragma once

#include <cstdint>
#include <string>

#include "server/common/status.h"
#include "server/volume/dicom_origin.h"

class DcmDataset;
class DcmFileFormat;
class DcmTagKey;

namespace vpm {

// The UIDs and times one export shares across its files.
struct DicomExportIds {
  std::string study_uid;               // the source's, or new when it has none
  std::string frame_of_reference_uid;  // the source's, or new
  std::string derived_series_uid;      // new
  std::string capture_series_uid;      // new
  std::string date;                    // YYYYMMDD, local time of the export
  std::string time;                    // HHMMSS
  int64_t derived_series_number = 0;   // the source's + 1000 (1000 without one)
};

// New UIDs (DCMTK's root), the source's study and frame of reference when
// `origin` has them.
DicomExportIds MakeDicomExportIds(const DicomOrigin* origin);

// Puts into `ds` the patient and study modules (copied from `origin`, empty
// type 2 values without it), the SOP common module (class, a new instance
// UID, creation date and time, the source's character set) and the general
// equipment module (Manufacturer "vpm"). `modality` and `series_uid` make
// the general series module; `number` is the InstanceNumber. `image_plane`:
// an image placed in the patient (CT, MR), which also takes the frame of
// reference and the acquisition attributes; a secondary capture takes
// neither. A `series_description` that is not ASCII (UTF-8) makes the
// dataset ISO_IR 192, the source's text converted to it; InvalidArgument when
// the source's declared set cannot be converted.
Status PutCommonModules(DcmDataset& ds, const DicomOrigin* origin, const DicomExportIds& ids,
                        bool image_plane, const char* sop_class_uid, const std::string& modality,
                        const std::string& series_uid, int64_t series_number,
                        const std::string& series_description, int64_t number);

// Sets `key` to `value` (multiple values joined by '\\'); Internal naming
// the attribute when DCMTK refuses it.
Status PutDicomString(DcmDataset& ds, const DcmTagKey& key, const std::string& value);

// The image pixel module's description of `rows` x `columns` pixels of
// `samples` samples (1: MONOCHROME2, 3: RGB, interleaved) of `bits` bits,
// signed or not; the pixel data itself is the caller's.
void PutImagePixelModule(DcmDataset& ds, int samples, int64_t rows, int64_t columns, int bits,
                         bool is_signed);

// `file` as a DICOM Part 10 file (explicit VR little endian).
Result<std::string> Part10Bytes(DcmFileFormat& file);

}  // namespace vpm

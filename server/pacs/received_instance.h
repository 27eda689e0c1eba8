// One instance a node sent to vpm's DICOM listener (C-STORE), checked
// before it is kept: an image of a series vpm can name safely.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "server/common/status.h"

namespace vpm::pacs {

// The attributes the received store indexes (patient identifiers are
// indexed, never logged).
struct ReceivedInstance {
  std::string study_uid;     // StudyInstanceUID, checked by CheckUid
  std::string series_uid;    // SeriesInstanceUID, checked
  std::string sop_uid;       // SOPInstanceUID, checked
  std::string patient_name;  // "^" kept
  std::string patient_id;
  std::string patient_birth_date;
  std::string study_date;
  std::string study_description;
  std::string accession_number;
  std::string modality;
  std::string series_description;
  std::string body_part;
  int64_t series_number = 0;
  bool has_image = false;  // PixelData (or float pixels), Rows and Columns
};

// Reads the Part 10 file `path` as received (large values, the pixels,
// are not loaded) and checks it: InvalidArgument when it does not parse or
// a UID is missing or not 1-64 digits and dots. `has_image` is false for
// what holds no image (a structured report, a dose report, a presentation
// state). Messages quote no value.
Result<ReceivedInstance> ReadReceivedInstance(const std::filesystem::path& path);

}  // namespace vpm::pacs

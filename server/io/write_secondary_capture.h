// A rendered frame as a DICOM Secondary Capture image in its source's
// study (DCMTK): the 3D view a surgeon planned with, beside the derived
// series.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/common/status.h"
#include "server/io/dicom_export_common.h"

namespace vpm {

// `rgba` (width * height * 4 bytes, rows top to bottom) as an RGB Secondary
// Capture Image Storage instance of the series ids.capture_series_uid
// (number ids.derived_series_number + 1), patient and study from `origin`
// (null: none), ImageType DERIVED\SECONDARY, ConversionType WSD
// (workstation). Errors: InvalidArgument for sizes that do not match;
// Internal when DCMTK cannot encode.
Result<std::string> WriteSecondaryCapture(const std::vector<uint8_t>& rgba, int width, int height,
                                          const DicomOrigin* origin, const DicomExportIds& ids,
                                          const std::string& description);

}  // namespace vpm

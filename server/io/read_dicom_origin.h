// The DicomOrigin of a series: what a derived series written back into its
// study copies (server/volume/dicom_origin.h), read from the headers of the
// series' files (DCMTK, leaving values over 4 KiB, the pixel data, unread).
#pragma once

#include <filesystem>
#include <vector>

#include "server/common/status.h"
#include "server/volume/dicom_origin.h"

namespace vpm {

// The attributes a derived image copies, as tags (0xGGGGEEEE): patient,
// study, frame of reference, modality, body part, patient position,
// character set, and the MR acquisition attributes the MR image module
// requires.
const std::vector<uint32_t>& DicomOriginTags();

// Reads `files` (one series, as ListDicomSeries groups them): the
// attributes of DicomOriginTags() from the first, and every file's SOP
// class, SOP instance and position. InvalidArgument (naming the file) for a
// file DCMTK cannot parse.
Result<DicomOrigin> ReadDicomOrigin(const std::vector<std::filesystem::path>& files);

}  // namespace vpm

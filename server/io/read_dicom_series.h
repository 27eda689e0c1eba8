// A DICOM series stored as one file per slice in a folder.
#pragma once

#include <filesystem>

#include "server/common/status.h"
#include "server/io/parse_dicom_source.h"
#include "server/volume/volume.h"

namespace vpm {

// Reads one series of the DICOM files in `folder` (not its subfolders; a
// file holds one slice, or several as an enhanced multi-frame image):
// `options.series` picks it (ListDicomSeries, ChooseDicomSeries: by default
// the largest CT or MR series; localizers and secondary captures never).
// The slices must share Rows, Columns, PixelSpacing and
// ImageOrientationPatient and lie at distinct positions along the slice
// normal (row x column direction); they are sorted by ImagePositionPatient
// along it.
// Output geometry (LPS): direction = (row dir, column dir, normal); spacing
// (PixelSpacing[1], PixelSpacing[0], slice gap along the normal;
// SliceThickness or 1 mm for one slice). An evenly spaced stack (gaps within
// 1% of their mean) whose slices line up along the normal is stored as is:
// dims (Columns, Rows, slices), origin = the first slice's position. Other
// stacks are resampled (ResampleShearedStack) onto a grid that covers them:
// a gantry-tilted or sheared stack (slices shifted across the normal), uneven
// gaps (to the smallest gap), or any stack given `options.spacing_mm`. The
// volume's notes() say what was corrected, and which series was read when
// the folder holds several. Values are rescaled (HU for CT).
// Errors: NotFound (no folder), InvalidArgument (no images, unknown series,
// mismatched slices, duplicate positions, bad files), ResourceExhausted (over
// `limits`, including the resampled grid), Unimplemented (see ParseDicomFrames).
Result<Volume> ReadDicomSeries(const std::filesystem::path& folder, const VolumeLimits& limits,
                               const DicomReadOptions& options = {});

}  // namespace vpm

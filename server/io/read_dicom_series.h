// A DICOM series stored as one file per slice in a folder.
#pragma once

#include <filesystem>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Reads every regular file in `folder` (not its subfolders). Files without
// the DICOM "DICM" prefix, and DICOM files without pixel data (DICOMDIR,
// reports), are skipped; any other unreadable file is an error naming it.
// The slices must form one series (one SeriesInstanceUID), share Rows,
// Columns, PixelSpacing and ImageOrientationPatient, and stack along the
// slice normal (row x column direction) at even gaps (1% of the mean gap)
// without duplicates. They are sorted by their ImagePositionPatient along
// that normal.
// Output geometry (LPS): dims (Columns, Rows, slices); spacing (PixelSpacing
// [1], PixelSpacing[0], mean gap; SliceThickness or 1 mm for one slice);
// origin = the first slice's position; direction = (row dir, column dir,
// normal). Values are rescaled (HU for CT).
// Errors: NotFound (no folder), InvalidArgument (no images, several series,
// mismatched slices, uneven or duplicate positions, bad files),
// ResourceExhausted (over `limits`), Unimplemented (see ParseDicomSlice; a
// tilted-gantry stack whose slices shift across the normal).
Result<Volume> ReadDicomSeries(const std::filesystem::path& folder, const VolumeLimits& limits);

}  // namespace vpm

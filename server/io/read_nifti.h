// NIfTI-1 and NIfTI-2 single-file volumes (.nii, .nii.gz).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Reads a .nii or .nii.gz file (gzip is recognised by its magic, not the
// name). Output: a Volume with values = scl_slope * stored + scl_inter where
// the slope is set (else the stored values), geometry in LPS (see
// nifti_geometry.h for the sform/qform precedence). Errors name the file:
// NotFound (missing), InvalidArgument (malformed: bad sizeof_hdr or magic,
// bad dims or spacing, unknown datatype, truncated data, gzip inflating past
// the declared size), ResourceExhausted (over `limits`, checked before any
// allocation of voxel data), Unimplemented (4D, complex/RGB, .hdr/.img pairs).
Result<Volume> ReadNifti(const std::filesystem::path& path, const VolumeLimits& limits);

// The same on the bytes of a file; `name` is used in messages and as source.
Result<Volume> ReadNiftiFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                   const VolumeLimits& limits);

}  // namespace vpm

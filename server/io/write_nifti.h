// Writes a volume as a NIfTI-1 single file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// The bytes of a NIfTI-1 .nii holding `volume`: little-endian voxels as the
// volume holds them, int16 (with scl_inter = the offset) or float32 (the
// values exactly, either way), spacing in pixdim, and the geometry converted to RAS
// twice, as sform and as qform (both code 1, scanner anatomical), so that
// readers using either see the same space. InvalidArgument when a dimension
// exceeds NIfTI-1's 32767.
Result<std::vector<uint8_t>> EncodeNifti(const Volume& volume);

// Writes EncodeNifti(volume) to `path`, gzip-compressed when the name ends in
// ".gz" (.nii.gz). Errors name the path.
Status WriteNifti(const Volume& volume, const std::filesystem::path& path);

}  // namespace vpm

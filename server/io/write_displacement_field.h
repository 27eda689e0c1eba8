// The deformation as a displacement field that 3D Slicer and ITK apply as a
// grid transform (docs/WARP.md, "The displacement field"): on the source
// grid, for each voxel x of the deformed frame, the offset (world LPS mm) to
// the source point seen there, so resampling the source at x + d(x) gives
// the deformed volume. Written as MetaImage (.mha: 3 float channels, ITK's
// DisplacementFieldTransform reads it) or NRRD (.nrrd: a 3-vector kind on a
// left-posterior-superior space).
#pragma once

#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// geometry: the source grid; offsets_lps_mm: geometry.voxel_count() vectors,
// x fastest. InvalidArgument for a count that does not match, a non-finite
// offset or a name not ending in .mha or .nrrd; Internal when the file
// cannot be written (the path named relative to nothing: as given).
Status WriteDisplacementField(const VolumeGeometry& geometry,
                              const std::vector<glm::vec3>& offsets_lps_mm,
                              const std::filesystem::path& path);

}  // namespace vpm

// CPU references of the volume warp J(x) = I(X(x)) (docs/ALGORITHM.md section 7;
// the GPU version is VolumeWarper in warp_volume.h).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/warp/backward_map_cpu.h"
#include "server/warp/backward_map_values.h"
#include "server/volume/volume.h"

namespace vpm {

// J through a backward map, the GPU's arithmetic in double: at every voxel
// x = index * spacing, X(x) = x + map.Sample(x).xyz, J(x) = SampleTrilinear(
// source, X(x)) (clamped indexing). `map` must cover the source's image box
// (map.extent_mm equal to source extent_mm, relative 1e-9). The result has
// the source's geometry, values float.
Result<Volume> WarpVolumeCpu(const Volume& source, const BackwardMapValues& map, int threads = 2);

// The exact warp: every voxel located in the deformed mesh on its own
// (TetLocator, eps as in options); J(x) = I(sum_i w_i rest_i) inside the
// mesh, I(x) outside. rest_mm, deformed_mm #V by 3 mm; tets #T by 4.
Result<Volume> WarpVolumeExactCpu(const Volume& source, const std::vector<glm::dvec3>& rest_mm,
                                  const std::vector<glm::dvec3>& deformed_mm,
                                  const std::vector<std::array<int32_t, 4>>& tets,
                                  const BackwardMapCpuOptions& options = {});

}  // namespace vpm

// CPU reference of the backward map (docs/ALGORITHM.md section 7; the GPU version
// is BackwardMap in backward_map.h): every grid point located in the
// deformed mesh with TetLocator, in double.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/warp/backward_map_values.h"

namespace vpm {

struct BackwardMapCpuOptions {
  double eps = kBackwardMapEps;  // barycentric tolerance, as on the GPU
  int threads = 2;
};

// Inputs:
//   extent_mm     3, the image box [0, extent] (mm), (n - 1) * spacing
//   map_dims      3, M grid points per axis, each >= 2
//   rest_mm       #V by 3, rest positions (mm, physical voxel space)
//   deformed_mm   #V by 3, deformed positions (mm)
//   tets          #T by 4 indices into the positions
// Output: the map; grid point (a, b, c) at p = (a, b, c) * extent / (M - 1)
// holds (X(p) - p, 1) where X(p) = sum_i w_i rest_i with w the barycentric
// weights of p in the smallest-index deformed tet whose weights are all
// >= -eps, and (0, 0, 0, 0) where no tet has them.
// Errors: InvalidArgument from CheckMapMesh / CheckMapGrid.
Result<BackwardMapValues> BackwardMapCpu(const glm::dvec3& extent_mm,
                                         const std::array<int64_t, 3>& map_dims,
                                         const std::vector<glm::dvec3>& rest_mm,
                                         const std::vector<glm::dvec3>& deformed_mm,
                                         const std::vector<std::array<int32_t, 4>>& tets,
                                         const BackwardMapCpuOptions& options = {});

}  // namespace vpm

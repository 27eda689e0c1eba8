// Input checks shared by the backward map on the GPU and its CPU reference,
// so that both reject the same inputs with the same messages.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"

namespace vpm {

// rest_mm, deformed_mm  #V by 3, mm, finite, the same count
// tets                  #T by 4 indices into them
// InvalidArgument naming the first offending vertex or tet.
Status CheckMapMesh(std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
                    std::span<const std::array<int32_t, 4>> tets);

// extent_mm: 3, finite and > 0 (a volume with at least 2 voxels per axis);
// map_dims: 3, each in [2, max_side]. InvalidArgument otherwise.
Status CheckMapGrid(const glm::dvec3& extent_mm, const std::array<int64_t, 3>& map_dims,
                    int64_t max_side);

}  // namespace vpm

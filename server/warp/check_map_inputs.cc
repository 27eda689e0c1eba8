#include "server/warp/check_map_inputs.h"

#include <cmath>

#include "server/common/finite_vec3.h"

namespace vpm {

Status CheckMapMesh(std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
                    std::span<const std::array<int32_t, 4>> tets) {
  if (rest_mm.size() != deformed_mm.size()) {
    return absl::InvalidArgumentError(StrCat("backward map: ", rest_mm.size(),
                                             " rest positions but ", deformed_mm.size(),
                                             " deformed positions"));
  }
  if (rest_mm.size() > size_t{INT32_MAX} || tets.size() > size_t{INT32_MAX}) {
    return absl::InvalidArgumentError("backward map: more than 2^31 - 1 vertices or tets");
  }
  for (size_t v = 0; v < rest_mm.size(); ++v) {
    if (!IsFinite(rest_mm[v]) || !IsFinite(deformed_mm[v])) {
      return absl::InvalidArgumentError(StrCat("backward map: vertex ", v, " has a non-finite ",
                                               IsFinite(rest_mm[v]) ? "deformed" : "rest",
                                               " position"));
    }
  }
  const int64_t vertex_count = static_cast<int64_t>(rest_mm.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int32_t v : tets[t]) {
      if (v < 0 || v >= vertex_count) {
        return absl::InvalidArgumentError(StrCat("backward map: tet ", t, " has vertex index ", v,
                                                 ", outside [0, ", vertex_count, ")"));
      }
    }
  }
  return absl::OkStatus();
}

Status CheckMapGrid(const glm::dvec3& extent_mm, const std::array<int64_t, 3>& map_dims,
                    int64_t max_side) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::isfinite(extent_mm[a]) && extent_mm[a] > 0.0)) {
      return absl::InvalidArgumentError(
          StrCat("backward map: the image box must have a positive extent on every axis "
                 "(at least 2 voxels); axis ",
                 a, " has ", extent_mm[a], " mm"));
    }
    if (map_dims[a] < 2 || map_dims[a] > max_side) {
      return absl::InvalidArgumentError(StrCat("backward map: ", map_dims[a],
                                               " grid points on axis ", a, "; must be in [2, ",
                                               max_side, "]"));
    }
  }
  return absl::OkStatus();
}

}  // namespace vpm

// Which backward-map grid points a deformed tet can own, and which tets an
// incremental map update must redo (backward_map.comp, docs/WARP.md).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

// An inclusive box of grid points; empty when lo > hi on some axis.
struct GridBox {
  glm::ivec3 lo{0};
  glm::ivec3 hi{-1};
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  bool operator==(const GridBox&) const = default;
};

// The grid points that may have all 4 barycentric weights >= -eps in the
// tet with deformed corners `corners` (mm): its bounding box widened by
// 4 * eps * its largest side (the weights >= -eps region is the tet scaled
// by 1 + 4 eps about its centroid) and by 1e-3 of a grid step for the
// GPU's float positions, clipped to [0, M - 1].
//   corners   4 positions, mm, finite
//   step_mm   3, grid step extent / (M - 1), mm
//   map_dims  3, M
GridBox TetGridBox(const std::array<glm::dvec3, 4>& corners, const glm::dvec3& step_mm,
                   const std::array<int64_t, 3>& map_dims, double eps);

// The tets (ascending indices) whose non-empty box in `tet_boxes` (#T)
// shares at least one grid point with a box of `region`.
std::vector<int32_t> TetsMeetingBoxes(std::span<const GridBox> tet_boxes,
                                      std::span<const GridBox> region);

}  // namespace vpm

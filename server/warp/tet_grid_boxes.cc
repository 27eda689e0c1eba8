#include "server/warp/tet_grid_boxes.h"

#include <algorithm>
#include <cmath>

namespace vpm {
namespace {

bool Meet(const GridBox& a, const GridBox& b) {
  return glm::all(glm::lessThanEqual(a.lo, b.hi)) && glm::all(glm::lessThanEqual(b.lo, a.hi));
}

}  // namespace

GridBox TetGridBox(const std::array<glm::dvec3, 4>& corners, const glm::dvec3& step_mm,
                   const std::array<int64_t, 3>& map_dims, double eps) {
  glm::dvec3 lo = corners[0], hi = corners[0];
  for (const glm::dvec3& c : corners) {
    lo = glm::min(lo, c);
    hi = glm::max(hi, c);
  }
  const glm::dvec3 size = hi - lo;
  const double widen_mm = 4.0 * eps * std::max({size.x, size.y, size.z});
  GridBox box;
  for (int a = 0; a < 3; ++a) {
    const double top = static_cast<double>(map_dims[a] - 1);
    // Clamped in double before the conversion, so huge positions cannot overflow.
    const double first = std::ceil((lo[a] - widen_mm) / step_mm[a] - 1e-3);
    const double last = std::floor((hi[a] + widen_mm) / step_mm[a] + 1e-3);
    box.lo[a] = static_cast<int>(std::clamp(first, 0.0, top + 1.0));
    box.hi[a] = static_cast<int>(std::clamp(last, -1.0, top));
  }
  return box;
}

std::vector<int32_t> TetsMeetingBoxes(std::span<const GridBox> tet_boxes,
                                      std::span<const GridBox> region) {
  std::vector<GridBox> boxes;
  GridBox bound;
  for (const GridBox& box : region) {
    if (box.empty()) continue;
    boxes.push_back(box);
    bound = bound.empty() ? box : GridBox{glm::min(bound.lo, box.lo), glm::max(bound.hi, box.hi)};
  }
  // Sorted by lo.x, so the scan for one tet stops at the first box that
  // starts beyond it.
  std::sort(boxes.begin(), boxes.end(),
            [](const GridBox& a, const GridBox& b) { return a.lo.x < b.lo.x; });
  std::vector<int32_t> tets;
  for (size_t t = 0; t < tet_boxes.size(); ++t) {
    const GridBox& box = tet_boxes[t];
    if (box.empty() || !Meet(box, bound)) continue;
    for (const GridBox& other : boxes) {
      if (other.lo.x > box.hi.x) break;
      if (Meet(box, other)) {
        tets.push_back(static_cast<int32_t>(t));
        break;
      }
    }
  }
  return tets;
}

}  // namespace vpm

#include "server/render/tet_grid_boxes.h"

#include <algorithm>
#include <cmath>

namespace vpm {
namespace {

constexpr int kBinShift = 3;  // bins of 8 grid points per axis

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
                                      std::span<const GridBox> region,
                                      const std::array<int64_t, 3>& map_dims) {
  const glm::ivec3 bins(static_cast<int>((map_dims[0] >> kBinShift) + 1),
                        static_cast<int>((map_dims[1] >> kBinShift) + 1),
                        static_cast<int>((map_dims[2] >> kBinShift) + 1));
  std::vector<uint8_t> marked(static_cast<size_t>(bins.x) * bins.y * bins.z, 0);
  auto for_bins = [&](const GridBox& box, auto&& fn) {
    const glm::ivec3 b0 = box.lo >> kBinShift, b1 = box.hi >> kBinShift;
    for (int z = b0.z; z <= b1.z; ++z) {
      for (int y = b0.y; y <= b1.y; ++y) {
        for (int x = b0.x; x <= b1.x; ++x) {
          if (fn(static_cast<size_t>(x) + bins.x * (static_cast<size_t>(y) + bins.y * z))) return;
        }
      }
    }
  };
  for (const GridBox& box : region) {
    if (box.empty()) continue;
    for_bins(box, [&](size_t b) {
      marked[b] = 1;
      return false;
    });
  }
  std::vector<int32_t> tets;
  for (size_t t = 0; t < tet_boxes.size(); ++t) {
    if (tet_boxes[t].empty()) continue;
    bool meets = false;
    for_bins(tet_boxes[t], [&](size_t b) { return meets = marked[b] != 0; });
    if (meets) tets.push_back(static_cast<int32_t>(t));
  }
  return tets;
}

}  // namespace vpm

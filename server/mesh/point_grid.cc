#include "server/mesh/point_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace vpm {

PointGrid::PointGrid(const std::vector<glm::dvec3>& points, double cell_mm) : cell_mm_(cell_mm) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(std::numeric_limits<double>::lowest());
  for (const auto& p : points) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (points.empty()) lo = hi = glm::dvec3(0.0);
  origin_ = lo;
  for (int a = 0; a < 3; ++a) {
    // Cap the bucket count per axis; a coarser grid stays correct, only slower.
    dims_[a] = std::clamp<int64_t>(static_cast<int64_t>((hi[a] - lo[a]) / cell_mm) + 1, 1, 4096);
  }
  if (dims_[0] * dims_[1] * dims_[2] > (int64_t{1} << 26)) dims_ = {1, 1, 1};
  // Widen the cell if the cap shrank the grid, so that a 3x3x3 visit still
  // covers a ball of radius cell_mm.
  for (int a = 0; a < 3; ++a) {
    cell_mm_ = std::max(cell_mm_, (hi[a] - lo[a]) / static_cast<double>(dims_[a]));
  }
  const int64_t buckets = dims_[0] * dims_[1] * dims_[2];
  std::vector<int64_t> bucket_of(points.size());
  start_.assign(buckets + 1, 0);
  for (size_t i = 0; i < points.size(); ++i) {
    const auto c = CellOf(points[i]);
    bucket_of[i] = c[0] + dims_[0] * (c[1] + dims_[1] * c[2]);
    ++start_[bucket_of[i] + 1];
  }
  for (int64_t b = 0; b < buckets; ++b) start_[b + 1] += start_[b];
  items_.resize(points.size());
  std::vector<int64_t> fill(start_.begin(), start_.end() - 1);
  positions_.resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    const int64_t slot = fill[bucket_of[i]]++;
    items_[slot] = static_cast<int64_t>(i);
    positions_[slot] = points[i];
  }
}

std::array<int64_t, 3> PointGrid::CellOf(const glm::dvec3& p) const {
  std::array<int64_t, 3> c;
  for (int a = 0; a < 3; ++a) {
    const double f = std::floor((p[a] - origin_[a]) / cell_mm_);
    c[a] = std::isfinite(f) ? std::clamp<int64_t>(static_cast<int64_t>(
                                                      std::clamp(f, -1.0, 1e9)),
                                                  0, dims_[a] - 1)
                            : 0;
  }
  return c;
}

}  // namespace vpm

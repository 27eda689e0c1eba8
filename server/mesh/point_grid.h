// A uniform grid of buckets over a fixed point set, for "all points within R
// of the points of a bucket" queries (docs/ALGORITHM.md step 2 asks for cell size
// R). Buckets hold point ids in increasing order, their positions stored in
// bucket order so that a scan is contiguous in memory.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace vpm {

class PointGrid {
 public:
  // points: #P positions (mm); cell_mm > 0.
  PointGrid(const std::vector<glm::dvec3>& points, double cell_mm);

  int64_t bucket_count() const { return static_cast<int64_t>(start_.size()) - 1; }
  // Bucket b holds the points in slots [slot_begin(b), slot_begin(b + 1)),
  // ids ascending: item(slot) is the point's id, position(slot) its position.
  int64_t slot_begin(int64_t b) const { return start_[b]; }
  int64_t item(int64_t slot) const { return items_[slot]; }
  const glm::dvec3& position(int64_t slot) const { return positions_[slot]; }

  // Calls fn(slot) for every slot of the 3x3x3 buckets around bucket b (b's
  // own included): a superset of the points within cell_mm of any of b's.
  template <typename Fn>
  void ForEachSlotAround(int64_t b, Fn&& fn) const {
    const int64_t cx = b % dims_[0], cy = (b / dims_[0]) % dims_[1], cz = b / (dims_[0] * dims_[1]);
    for (int64_t z = std::max<int64_t>(cz - 1, 0); z <= std::min(cz + 1, dims_[2] - 1); ++z)
      for (int64_t y = std::max<int64_t>(cy - 1, 0); y <= std::min(cy + 1, dims_[1] - 1); ++y) {
        const int64_t row = dims_[0] * (y + dims_[1] * z);
        const int64_t x0 = std::max<int64_t>(cx - 1, 0), x1 = std::min(cx + 1, dims_[0] - 1);
        // Buckets x0..x1 of one row are contiguous in slot order.
        for (int64_t n = start_[row + x0]; n < start_[row + x1 + 1]; ++n) fn(n);
      }
  }

 private:
  std::array<int64_t, 3> CellOf(const glm::dvec3& p) const;

  glm::dvec3 origin_;
  double cell_mm_;
  std::array<int64_t, 3> dims_;
  std::vector<int64_t> start_;  // CSR: bucket b holds items_[start_[b] .. start_[b+1])
  std::vector<int64_t> items_;
  std::vector<glm::dvec3> positions_;  // positions_[n] is the position of items_[n]
};

// |a - b| computed in one fixed order, so that every caller gets the same bits.
inline double PointDistance(const glm::dvec3& a, const glm::dvec3& b) {
  const double dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace vpm

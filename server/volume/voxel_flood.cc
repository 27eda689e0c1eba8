#include "server/volume/voxel_flood.h"

#include <deque>
#include <unordered_set>

namespace vpm {

VoxelFlood FloodFill(const Volume& volume, const std::array<int64_t, 3>& seed,
                     const VoxelPredicate& accept, int64_t max_voxels, Connectivity connectivity) {
  VoxelFlood out;
  const auto& dims = volume.dims();
  const auto inside = [&](int64_t i, int64_t j, int64_t k) {
    return i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2];
  };
  if (!inside(seed[0], seed[1], seed[2])) return out;
  const int64_t first = volume.LinearIndex(seed[0], seed[1], seed[2]);
  if (!accept(seed[0], seed[1], seed[2], first)) return out;
  std::unordered_set<int64_t> seen;
  seen.reserve(static_cast<size_t>(std::min<int64_t>(max_voxels, 1 << 20)) * 2);
  std::deque<std::array<int64_t, 3>> queue;
  seen.insert(first);
  queue.push_back(seed);
  std::vector<std::array<int, 3>> steps;
  for (int c = -1; c <= 1; ++c)
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a) {
        const int nonzero = (a != 0) + (b != 0) + (c != 0);
        if (nonzero == 1 || (nonzero > 1 && connectivity == Connectivity::kFull26)) {
          steps.push_back({a, b, c});
        }
      }
  while (!queue.empty()) {
    if (static_cast<int64_t>(out.voxels.size()) >= max_voxels) {
      out.complete = false;
      return out;
    }
    const auto [i, j, k] = queue.front();
    queue.pop_front();
    out.voxels.push_back(volume.LinearIndex(i, j, k));
    for (const auto& s : steps) {
      const int64_t a = i + s[0], b = j + s[1], c = k + s[2];
      if (!inside(a, b, c)) continue;
      const int64_t linear = volume.LinearIndex(a, b, c);
      if (seen.count(linear) != 0 || !accept(a, b, c, linear)) continue;
      seen.insert(linear);
      queue.push_back({a, b, c});
    }
  }
  return out;
}

}  // namespace vpm

#include "server/volume/block_average.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vpm {

bool BlockGrid::CellOf(int64_t i, int64_t j, int64_t k, std::array<int64_t, 3>& cell) const {
  const int64_t index[3] = {i, j, k};
  for (int a = 0; a < 3; ++a) {
    if (index[a] < lo[a]) return false;
    cell[a] = (index[a] - lo[a]) / factor[a];
    if (cell[a] >= dims[a]) return false;
  }
  return true;
}

glm::dvec3 BlockGrid::VolumeToGrid(const glm::dvec3& p_mm, const glm::dvec3& spacing_mm) const {
  glm::dvec3 out;
  for (int a = 0; a < 3; ++a) {
    // Voxel index lo + factor c + (factor - 1) / 2 is cell c's centre.
    const double centre0 = double(lo[a]) + 0.5 * double(factor[a] - 1);
    out[a] = (p_mm[a] / spacing_mm[a] - centre0) * spacing_mm[a];
  }
  return out;
}

std::array<int64_t, 3> BlockFactor(const glm::dvec3& spacing_mm, double cell_mm) {
  std::array<int64_t, 3> factor{1, 1, 1};
  if (!(cell_mm > 0.0)) return factor;
  for (int a = 0; a < 3; ++a) {
    factor[a] = std::max<int64_t>(1, static_cast<int64_t>(std::floor(cell_mm / spacing_mm[a])));
  }
  return factor;
}

Result<Volume> BlockAverage(const Volume& volume, const std::array<int64_t, 3>& lo,
                            const std::array<int64_t, 3>& size,
                            const std::array<int64_t, 3>& factor, BlockGrid& grid) {
  const auto& dims = volume.dims();
  std::array<int64_t, 3> hi{};  // one past the box's last voxel
  for (int a = 0; a < 3; ++a) {
    if (factor[a] < 1) return absl::InvalidArgumentError("block average: factor below 1");
    grid.lo[a] = std::clamp<int64_t>(lo[a], 0, dims[a]);
    hi[a] = std::clamp<int64_t>(lo[a] + size[a], 0, dims[a]);
    if (hi[a] <= grid.lo[a]) return absl::InvalidArgumentError("block average: empty box");
    grid.factor[a] = factor[a];
    grid.dims[a] = (hi[a] - grid.lo[a] + factor[a] - 1) / factor[a];
  }
  VolumeGeometry g;
  g.dims = grid.dims;
  g.spacing_mm = volume.spacing_mm() * glm::dvec3(factor[0], factor[1], factor[2]);
  std::vector<double> sum(static_cast<size_t>(g.voxel_count()), 0.0);
  std::vector<int32_t> count(sum.size(), 0);
  // Along memory: each voxel of the box added to its cell.
  for (int64_t k = grid.lo[2]; k < hi[2]; ++k) {
    const int64_t ck = (k - grid.lo[2]) / factor[2];
    for (int64_t j = grid.lo[1]; j < hi[1]; ++j) {
      const int64_t row = grid.dims[0] * ((j - grid.lo[1]) / factor[1] + grid.dims[1] * ck);
      for (int64_t i = grid.lo[0]; i < hi[0]; ++i) {
        const size_t cell = static_cast<size_t>(row + (i - grid.lo[0]) / factor[0]);
        sum[cell] += volume.At(i, j, k);
        ++count[cell];
      }
    }
  }
  std::vector<float> values(sum.size());
  for (size_t n = 0; n < values.size(); ++n) values[n] = static_cast<float>(sum[n] / count[n]);
  return Volume::Create(g, std::move(values), UnboundedVolumeLimits());
}

}  // namespace vpm

#include "server/volume/sample_trilinear.h"

#include <algorithm>
#include <cmath>

namespace vpm {

double SampleTrilinear(const Volume& volume, const glm::dvec3& p_mm) {
  const auto& dims = volume.dims();
  int64_t i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double n1 = static_cast<double>(dims[a] - 1);
    double index = p_mm[a] / volume.spacing_mm()[a];
    index = std::isnan(index) ? 0.0 : std::clamp(index, 0.0, n1);
    // The lower corner stays one below the last voxel so the upper exists
    // (its weight is then exactly 1 at the far face).
    const double base = std::min(std::floor(index), std::max(n1 - 1.0, 0.0));
    i0[a] = static_cast<int64_t>(base);
    f[a] = index - base;
  }
  double value = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const int di = corner & 1, dj = (corner >> 1) & 1, dk = (corner >> 2) & 1;
    const double w = (di ? f[0] : 1.0 - f[0]) * (dj ? f[1] : 1.0 - f[1]) * (dk ? f[2] : 1.0 - f[2]);
    if (w == 0.0) continue;
    value += w * volume.AtClamped(i0[0] + di, i0[1] + dj, i0[2] + dk);
  }
  return value;
}

}  // namespace vpm

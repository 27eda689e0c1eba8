#include "server/warp/backward_map_values.h"

#include <algorithm>
#include <cmath>

namespace vpm {

std::array<int64_t, 3> DefaultBackwardMapDims(const std::array<int64_t, 3>& volume_dims) {
  std::array<int64_t, 3> m;
  for (int a = 0; a < 3; ++a) {
    m[a] = std::clamp<int64_t>((volume_dims[a] + 3) / 4, 2, kMaxDefaultMapPointsPerAxis);
  }
  return m;
}

glm::dvec3 BackwardMapValues::StepMm() const {
  return extent_mm / glm::dvec3(dims[0] - 1, dims[1] - 1, dims[2] - 1);
}

glm::dvec4 BackwardMapValues::Sample(const glm::dvec3& p_mm) const {
  int64_t i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double m1 = static_cast<double>(dims[a] - 1);
    double index = p_mm[a] / extent_mm[a] * m1;
    index = std::isnan(index) ? 0.0 : std::clamp(index, 0.0, m1);
    const double base = std::min(std::floor(index), m1 - 1.0);
    i0[a] = static_cast<int64_t>(base);
    f[a] = index - base;
  }
  glm::dvec4 value(0.0);
  for (int corner = 0; corner < 8; ++corner) {
    const int da = corner & 1, db = (corner >> 1) & 1, dc = (corner >> 2) & 1;
    const double w = (da ? f[0] : 1.0 - f[0]) * (db ? f[1] : 1.0 - f[1]) * (dc ? f[2] : 1.0 - f[2]);
    if (w == 0.0) continue;
    value += w * glm::dvec4(At(i0[0] + da, i0[1] + db, i0[2] + dc));
  }
  return value;
}

}  // namespace vpm

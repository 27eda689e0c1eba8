#include "server/warp/tet_displacement_frame.h"

#include <cmath>

namespace vpm {

std::array<glm::vec4, 4> TetDisplacementFrame(const std::array<glm::dvec3, 4>& rest_mm,
                                              const std::array<glm::dvec3, 4>& deformed_mm) {
  const glm::dvec3 d0 = deformed_mm[0];
  const glm::dvec3 o0 = rest_mm[0] - d0;
  // Columns: edges from vertex 0 (deformed), and the offsets' differences.
  const glm::dmat3 edges(deformed_mm[1] - d0, deformed_mm[2] - d0, deformed_mm[3] - d0);
  const glm::dmat3 offsets((rest_mm[1] - deformed_mm[1]) - o0, (rest_mm[2] - deformed_mm[2]) - o0,
                           (rest_mm[3] - deformed_mm[3]) - o0);
  const double det = glm::determinant(edges);
  glm::dmat3 a(0.0);
  if (det != 0.0 && std::isfinite(det)) a = offsets * glm::inverse(edges);
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      if (!std::isfinite(a[c][r])) a = glm::dmat3(0.0);
    }
  }
  // glm is column-major: a[c][r] is row r, column c.
  auto row = [&](int r) { return glm::vec4(a[0][r], a[1][r], a[2][r], o0[r]); };
  return {glm::vec4(glm::vec3(d0), 0.0f), row(0), row(1), row(2)};
}

}  // namespace vpm

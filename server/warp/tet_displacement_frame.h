// The backward map's value inside one deformed tet as an affine function of
// the grid point (backward_map_write.comp, docs/WARP.md).
#pragma once

#include <array>

#include <glm/glm.hpp>

namespace vpm {

// Inside the tet, X(p) - p = sum_i w_i(p) (rest_i - deformed_i) with the
// barycentric weights w_i of p in the deformed tet, which is affine in p:
// o0 + A (p - d0), d0 = deformed_0, o_i = rest_i - deformed_i,
// A = [o1 - o0, o2 - o0, o3 - o0] [d1 - d0, d2 - d0, d3 - d0]^-1 (3x3),
// composed in double and rounded to float. Returned as the 4 vec4 the
// kernel reads: (d0 mm, 0), (A row 0, o0.x), (A row 1, o0.y), (A row 2, o0.z).
// A flat tet (zero or non-finite determinant) owns no grid point; it gets
// A = 0.
//   rest_mm, deformed_mm  the tet's 4 corners, mm, finite
std::array<glm::vec4, 4> TetDisplacementFrame(const std::array<glm::dvec3, 4>& rest_mm,
                                              const std::array<glm::dvec3, 4>& deformed_mm);

}  // namespace vpm

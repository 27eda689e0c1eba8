// The linear (4-node) isotropic tetrahedron: rest geometry, shape-function
// gradients, stress and the 12x12 rest stiffness (units: fem_units.h).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <glm/glm.hpp>

#include "server/common/status.h"

namespace vpm {

struct TetElement {
  std::array<int32_t, 4> vertices{};  // indices into the mesh's vertices
  double volume_mm3 = 0.0;            // rest volume, > 0
  // Column a: gradient of the linear shape function of vertex a over the
  // rest tet, 1/mm. The columns sum to 0.
  Eigen::Matrix<double, 3, 4> grad_per_mm = Eigen::Matrix<double, 3, 4>::Zero();
  double lambda_n_per_mm2 = 0.0;  // Lame parameters
  double mu_n_per_mm2 = 0.0;
};

// One element from its rest corners.
//   vertices        4 indices (stored, not checked here)
//   rest_mm         4 corners, mm, positive orientation
//   young_n_per_mm2 Young's modulus, N/mm^2, > 0
//   poisson         in (-1, 0.5)
// Fails (InvalidArgument) on a flat, inverted or non-finite tet.
Result<TetElement> MakeTetElement(const std::array<int32_t, 4>& vertices,
                                  const std::array<glm::dvec3, 4>& rest_mm, double young_n_per_mm2,
                                  double poisson);

// All elements of a mesh.
//   rest_mm          #V by 3, mm
//   tets             #T by 4 indices into rest_mm, positive orientation
//   young_n_per_mm2  #T moduli, N/mm^2
// Output: #T elements. Fails on an index out of range, a size mismatch or a
// bad tet (the message names it).
Result<std::vector<TetElement>> MakeTetElements(const std::vector<glm::dvec3>& rest_mm,
                                                const std::vector<std::array<int32_t, 4>>& tets,
                                                const std::vector<double>& young_n_per_mm2,
                                                double poisson);

// The element's 4 corner vectors from a 3*#V vector v (vertex i's axis k at
// 3i + k) as 3 by 4, column a for corner a.
inline Eigen::Matrix<double, 3, 4> GatherCorners(const TetElement& element,
                                                 const Eigen::VectorXd& v) {
  Eigen::Matrix<double, 3, 4> corners;
  for (int a = 0; a < 4; ++a) corners.col(a) = v.segment<3>(3 * element.vertices[a]);
  return corners;
}

// Displacement gradient sum_a u_a grad_a^T (3 by 3, dimensionless) of the
// corner displacements u (3 by 4, mm; column a for vertex a).
inline Eigen::Matrix3d DisplacementGradient(const TetElement& element,
                                            const Eigen::Matrix<double, 3, 4>& u_mm) {
  return u_mm * element.grad_per_mm.transpose();
}

// Linear-elastic stress of the element for a displacement gradient H
// (3 by 3, dimensionless; only its symmetric part counts):
//   sigma = lambda tr(eps) I + 2 mu eps,  eps = (H + H^T) / 2.   N/mm^2.
inline Eigen::Matrix3d LinearStress(const TetElement& element, const Eigen::Matrix3d& h) {
  const Eigen::Matrix3d eps = 0.5 * (h + h.transpose());
  return element.lambda_n_per_mm2 * eps.trace() * Eigen::Matrix3d::Identity() +
         2.0 * element.mu_n_per_mm2 * eps;
}

// Nodal forces of a uniform stress over the rest element, V sigma grad_a
// (3 by 4, N; column a on vertex a). With sigma = LinearStress(H(u)) this is
// K0 u: the elastic forces, pointing against the deformation's gradient.
inline Eigen::Matrix<double, 3, 4> StressNodalForces(const TetElement& element,
                                                     const Eigen::Matrix3d& sigma) {
  return element.volume_mm3 * sigma * element.grad_per_mm;
}

// The rest (linear) element stiffness K0, 12 by 12, N/mm, rows and columns
// ordered (vertex a, axis i) -> 3a + i:
//   K_ab = V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I).
// Symmetric positive semi-definite with the 6 rigid motions as null space.
Eigen::Matrix<double, 12, 12> ElementStiffness(const TetElement& element);

}  // namespace vpm

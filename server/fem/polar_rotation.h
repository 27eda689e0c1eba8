// The rotation of a deformation gradient (the corotational frame).
#pragma once

#include <Eigen/Core>

namespace vpm {

// The proper rotation R (det +1) nearest to F in the Frobenius norm, i.e. the
// maximiser of tr(R^T F) over SO(3):
//   R = U diag(1, 1, sign det(U V^T)) V^T  for the SVD F = U S V^T
// (singular values descending). For det F > 0 this is the rotation of the
// polar decomposition F = R S; for an inverted element (det F < 0) the
// reflection is moved onto the smallest singular direction instead of being
// returned, so R stays a rotation. Scale-invariant: R(c F) = R(F) for c > 0.
//   f     3 by 3 deformation gradient, dimensionless
// Output: 3 by 3 rotation. Identity for F = 0 or a non-finite F.
//
// Well-conditioned F (the common case) takes Higham's scaled Newton
// iteration, ~0.1 us; nearly flat or inverted ones take JacobiSVD.
Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& f);

}  // namespace vpm

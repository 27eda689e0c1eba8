// The corotated element operator: per-element rotations, elastic forces and
// the tangent stiffness applied to a vector, matrix-free.
//
// For element e with rest corners X, current corners x = X + u, rotation R
// (PolarRotation of F = I + sum_a u_a grad_a^T, F = R S), rest stiffness K0:
//   forces   f_e = R K0 (R^T x - X) = V R sigma(S - I) grad
//            (exactly the gradient of the energy V (mu |S-I|^2 + lambda/2 tr(S-I)^2))
//   tangent  K_e = R K0 R^T + K_twist
// R K0 R^T is the classic corotational stiffness (rotation frozen). K_twist
// is the part of the exact energy Hessian that comes from the rotation's own
// derivative, clamped to be positive semi-definite: with G = R^T dF and
// a = axial(G - G^T) (the element's infinitesimal twist),
//   dP_twist = R [Q a]_x,  Q = mu I + (lambda tr(S-I) - 2 mu) (tr(S) I - S)^-1,
// Q's eigenvalues clamped at 0 (they turn negative in compression). Q = 0 at
// rest. Without it, the fixed-point iteration on R K0 R^T alone over-corrects
// the soft rotation modes of a stressed body and diverges, e.g. on a slender
// bar stretched by 10% (tests/fem/uniaxial_bar_test.cc).
// With the inversion barrier on (inversion_barrier.h), each element's barrier
// forces and tangent are added to these.
// All vectors are 3 * #V long, vertex v's axis i at 3v + i.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "server/fem/inversion_barrier.h"
#include "server/fem/tet_element.h"

namespace vpm {

enum class FemMethod {
  kLinear,                  // R = I: plain linear FEM
  kCorotational,            // tangent R K0 R^T (rotations frozen per iteration)
  kCorotationalConsistent,  // tangent R K0 R^T + K_twist (projected Newton)
};

// Q is O(strain); below this strain (Frobenius norm of sym(R^T F - I),
// dimensionless) it is taken as 0. The tangent only steers the iterations
// (the forces stay exact), and 1e-3 of K0 changes their course by nothing
// measurable while most elements away from the handles skip the term.
inline constexpr double kTwistMinStrain = 1e-3;

// Per-element state of the tangent: rotation R and twist stiffness Q
// (N/mm^2, symmetric positive semi-definite; zero unless consistent).
struct CorotatedFrames {
  std::vector<Eigen::Matrix3d> rotations;  // #T
  std::vector<Eigen::Matrix3d> twist;      // #T, or empty for none
  std::vector<uint8_t> twisted;            // #T (with twist): 1 where Q != 0
  std::vector<BarrierTerm> barrier;        // #T with the barrier on, else empty

  // Q of element t, or null where it is 0 or absent.
  const Eigen::Matrix3d* Twist(size_t t) const {
    return !twist.empty() && twisted[t] ? &twist[t] : nullptr;
  }
  // Element t's barrier term, or null where it is inactive or off.
  const BarrierTerm* Barrier(size_t t) const {
    return !barrier.empty() && barrier[t].active ? &barrier[t] : nullptr;
  }
};

// Rotations and elastic forces at displacement u.
//   elements  #T
//   u_mm      3*#V displacements, mm
//   method    which tangent the frames describe
//   threads   threads to split the elements between (ParallelChunks)
//   inversion_barrier  add the barrier's forces (and keep its terms)
// Outputs:
//   frames    #T rotations (identity for kLinear), for the consistent
//             method #T twist matrices, with the barrier #T barrier terms
//             (resized)
//   forces_n  3*#V elastic (internal) forces, N (resized, overwritten)
void CorotatedForces(const std::vector<TetElement>& elements, const Eigen::VectorXd& u_mm,
                     FemMethod method, CorotatedFrames& frames, Eigen::VectorXd& forces_n,
                     int threads = 1, bool inversion_barrier = false);

// Tangent of one element applied to its corner vectors v (3 by 4, mm):
// (R K0 R^T + K_twist + K_barrier) v as 3 by 4 nodal forces, N. twist and
// barrier may be null.
Eigen::Matrix<double, 3, 4> ApplyElementTangent(const TetElement& element,
                                                const Eigen::Matrix3d& rotation,
                                                const Eigen::Matrix3d* twist,
                                                const Eigen::Matrix<double, 3, 4>& v_mm,
                                                const BarrierTerm* barrier = nullptr);

// y = K v = sum_e K_e v_e with the frames from CorotatedForces.
//   v_mm  3*#V
// Output: y_n, 3*#V, N (resized, overwritten).
void ApplyCorotatedStiffness(const std::vector<TetElement>& elements, const CorotatedFrames& frames,
                             const Eigen::VectorXd& v_mm, Eigen::VectorXd& y_n, int threads = 1);

// Elastic energy sum_e V (mu eps:eps + lambda/2 tr(eps)^2) with
// eps = sym(R^T F - I), N*mm; rotations as from CorotatedForces at u_mm;
// plus the barrier energies when inversion_barrier.
double CorotatedEnergy(const std::vector<TetElement>& elements,
                       const std::vector<Eigen::Matrix3d>& rotations, const Eigen::VectorXd& u_mm,
                       bool inversion_barrier = false);

}  // namespace vpm

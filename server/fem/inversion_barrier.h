// A volumetric barrier that keeps elements from inverting.
//
// docs/ALGORITHM.md section 6 asks for no inverted tet (signed volume <= 0) after
// drags of up to 1.5 h, but corotated linear elasticity (section 5) has no
// barrier against collapse: its energy stays finite as an element is crushed
// flat and through itself, so a handle dragged further than the tets around
// it are long pushes through them (docs/FEM.md). This term is added to the
// corotated energy of an element only while its volume ratio J = det F is
// below kBarrierOnsetVolumeRatio:
//   E_b = V k b(J),  b(J) = -(J - J0)^2 ln(J / J0)  for 0 < J < J0, else 0
// (the barrier of Incremental Potential Contact, Li et al. 2020, on J). b is
// twice continuously differentiable at J0 (b = b' = b'' = 0 there), so an
// element compressed less than that sees exactly the corotated model; b grows
// without bound as J -> 0, so a solver that never steps across J = 0 keeps
// every element's orientation. k = lambda + 2 mu of the element (its P-wave
// modulus, N/mm^2), so the barrier scales with the material like the rest.
//   forces   f_a = V k b'(J) cof(F) grad_a
//   tangent  V k b''(J) (cof(F) : dF) cof(F) grad_a, positive semi-definite
//            (the b'(J) d cof(F) part, indefinite, is left out as in
//            projected Newton; it only steers the iterations)
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "server/fem/tet_element.h"

namespace vpm {

// J0: the volume ratio (deformed / rest volume, dimensionless) below which
// the barrier acts. 0.25: soft tissue compressed to a quarter of its volume is
// already far outside linear elasticity, and the drags of section 6 leave
// every element above it except those in front of a point-like handle.
inline constexpr double kBarrierOnsetVolumeRatio = 0.25;

// The barrier of one element at deformation gradient F (3 by 3,
// dimensionless), or inactive (J >= J0 or J <= 0).
struct BarrierTerm {
  bool active = false;
  Eigen::Matrix3d cofactor = Eigen::Matrix3d::Zero();  // cof(F) = J F^-T
  double energy_n_mm = 0.0;                            // V k b(J), N*mm
  double stress_scale_n_per_mm2 = 0.0;                 // k b'(J), N/mm^2 (< 0)
  double curvature_n_per_mm2 = 0.0;                    // k b''(J), N/mm^2 (> 0)
};

// The barrier term of an element at F = I + displacement gradient.
BarrierTerm EvaluateBarrier(const TetElement& element, const Eigen::Matrix3d& deformation_gradient);

// Nodal forces of the barrier (3 by 4, N; column a on vertex a); zero when
// inactive. They point like the elastic forces: against compression.
Eigen::Matrix<double, 3, 4> BarrierForces(const TetElement& element, const BarrierTerm& term);

// The barrier tangent applied to corner vectors v (3 by 4, mm), N.
Eigen::Matrix<double, 3, 4> ApplyBarrierTangent(const TetElement& element, const BarrierTerm& term,
                                                const Eigen::Matrix<double, 3, 4>& v_mm);

// Volume ratio det(I + grad u) of element `element` at displacements u_mm
// (3*#V, mm).
double VolumeRatio(const TetElement& element, const Eigen::VectorXd& u_mm);

// The largest alpha in {1, 1/2, 1/4, ...} (down to min_alpha; 0 if none) such
// that every element keeps J(u + alpha du) >= keep * min(J(u), J0): an
// element may lose at most (1 - keep) of its volume ratio per step once it
// is near the barrier, so a state with every J > 0 stays so. Elements with
// J(u) <= 0 (inverted before the barrier was on) are not checked, nor those
// flagged in `skip` (#T, or empty for none).
//   u_mm, du_mm  3*#V, mm
//   keep         in (0, 1), dimensionless
double FeasibleStepFraction(const std::vector<TetElement>& elements, const Eigen::VectorXd& u_mm,
                            const Eigen::VectorXd& du_mm, double keep = 0.2,
                            double min_alpha = 1.0 / 1048576.0,
                            const std::vector<uint8_t>& skip = {});

}  // namespace vpm

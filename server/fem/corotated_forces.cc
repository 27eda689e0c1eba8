#include "server/fem/corotated_forces.h"

#include <algorithm>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "server/common/parallel_chunks.h"
#include "server/fem/polar_rotation.h"

namespace vpm {
namespace {

// R^T F - I with F = I + G, computed without forming F so that small
// displacements keep their relative precision.
Eigen::Matrix3d CorotatedStrainSource(const Eigen::Matrix3d& r, const Eigen::Matrix3d& g) {
  return r.transpose() * g + (r.transpose() - Eigen::Matrix3d::Identity());
}

Eigen::Matrix3d Cross(const Eigen::Vector3d& b) {
  Eigen::Matrix3d m;
  m << 0.0, -b.z(), b.y(), b.z(), 0.0, -b.x(), -b.y(), b.x(), 0.0;
  return m;
}

// True when the symmetric 3x3 matrix minus eps I is positive definite
// (Sylvester's criterion on the leading minors).
bool PositiveDefinite(Eigen::Matrix3d m, double eps) {
  m.diagonal().array() -= eps;
  return m(0, 0) > 0.0 && m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0) > 0.0 && m.determinant() > 0.0;
}

// Q of the header, eigenvalues clamped at 0. s_minus_i = sym(R^T F - I).
// Most elements need no clamping; they skip the eigen-decomposition.
Eigen::Matrix3d TwistStiffness(const TetElement& element, const Eigen::Matrix3d& s_minus_i) {
  constexpr double kMinPairSum = 1e-6;  // s_j + s_k below this: no twist stiffness
  const double mu = element.mu_n_per_mm2;
  const double c = element.lambda_n_per_mm2 * s_minus_i.trace() - 2.0 * mu;
  const Eigen::Matrix3d m = (s_minus_i.trace() + 3.0) * Eigen::Matrix3d::Identity() - s_minus_i -
                            Eigen::Matrix3d::Identity();  // tr(S) I - S
  if (PositiveDefinite(m, kMinPairSum)) {
    const Eigen::Matrix3d q = mu * Eigen::Matrix3d::Identity() + c * m.inverse();
    if (PositiveDefinite(q, 0.0)) return q;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(s_minus_i);
  const Eigen::Vector3d s = eigen.eigenvalues().array() + 1.0;  // eigenvalues of S
  Eigen::Vector3d q;
  for (int i = 0; i < 3; ++i) {
    const double pair = s.sum() - s[i];  // eigenvalue of tr(S) I - S: s_j + s_k
    q[i] = pair > kMinPairSum ? std::max(0.0, mu + c / pair) : 0.0;
  }
  return eigen.eigenvectors() * q.asDiagonal() * eigen.eigenvectors().transpose();
}

// out (dofs entries) = the sum over elements of their nodal vectors
// scattered to their corners; element_vector(t, f) fills f (3 by 4) for
// element t and returns false when it adds nothing. The elements are split
// between `threads` (ParallelChunks), each summing into its own vector.
template <typename ElementVector>
void SumOverElements(const std::vector<TetElement>& elements, int64_t dofs, int threads,
                     const ElementVector& element_vector, Eigen::VectorXd& out) {
  std::vector<Eigen::VectorXd> parts(std::max(1, threads));
  ParallelChunks(
      threads, static_cast<int64_t>(elements.size()), [&](int64_t begin, int64_t end, int part) {
        Eigen::VectorXd& sum = parts[part];
        sum.setZero(dofs);
        Eigen::Matrix<double, 3, 4> f;
        for (int64_t t = begin; t < end; ++t) {
          if (!element_vector(t, f)) continue;
          for (int a = 0; a < 4; ++a) sum.segment<3>(3 * elements[t].vertices[a]) += f.col(a);
        }
      });
  // The first part is always filled; others only when their chunk ran.
  out = std::move(parts[0]);
  for (size_t p = 1; p < parts.size(); ++p) {
    if (parts[p].size() == out.size()) out += parts[p];
  }
}

}  // namespace

void CorotatedForces(const std::vector<TetElement>& elements, const Eigen::VectorXd& u_mm,
                     FemMethod method, CorotatedFrames& frames, Eigen::VectorXd& forces_n,
                     int threads, bool inversion_barrier) {
  frames.rotations.resize(elements.size());
  if (method == FemMethod::kCorotationalConsistent) {
    frames.twist.resize(elements.size());
    frames.twisted.assign(elements.size(), 0);
  } else {
    frames.twist.clear();
    frames.twisted.clear();
  }
  if (inversion_barrier) {
    frames.barrier.resize(elements.size());
  } else {
    frames.barrier.clear();
  }
  const auto element_forces = [&](int64_t t, Eigen::Matrix<double, 3, 4>& f) {
    const TetElement& element = elements[t];
    const Eigen::Matrix3d g = DisplacementGradient(element, GatherCorners(element, u_mm));
    const Eigen::Matrix3d r = method == FemMethod::kLinear
                                  ? Eigen::Matrix3d::Identity()
                                  : PolarRotation(Eigen::Matrix3d::Identity() + g);
    frames.rotations[t] = r;
    const Eigen::Matrix3d h = CorotatedStrainSource(r, g);
    if (!frames.twist.empty()) {
      const Eigen::Matrix3d strain = 0.5 * (h + h.transpose());
      if (strain.squaredNorm() >= kTwistMinStrain * kTwistMinStrain) {
        frames.twist[t] = TwistStiffness(element, strain);
        frames.twisted[t] = 1;
      }
    }
    f = r * StressNodalForces(element, LinearStress(element, h));
    if (inversion_barrier) {
      frames.barrier[t] = EvaluateBarrier(element, Eigen::Matrix3d::Identity() + g);
      f += BarrierForces(element, frames.barrier[t]);
    }
    return true;
  };
  SumOverElements(elements, u_mm.size(), threads, element_forces, forces_n);
}

Eigen::Matrix<double, 3, 4> ApplyElementTangent(const TetElement& element,
                                                const Eigen::Matrix3d& rotation,
                                                const Eigen::Matrix3d* twist,
                                                const Eigen::Matrix<double, 3, 4>& v_mm,
                                                const BarrierTerm* barrier) {
  const Eigen::Matrix3d g = rotation.transpose() * DisplacementGradient(element, v_mm);
  Eigen::Matrix3d p = LinearStress(element, g);
  if (twist != nullptr) {
    const Eigen::Vector3d a(g(2, 1) - g(1, 2), g(0, 2) - g(2, 0), g(1, 0) - g(0, 1));
    p += Cross(*twist * a);
  }
  Eigen::Matrix<double, 3, 4> f = rotation * StressNodalForces(element, p);
  if (barrier != nullptr) f += ApplyBarrierTangent(element, *barrier, v_mm);
  return f;
}

void ApplyCorotatedStiffness(const std::vector<TetElement>& elements, const CorotatedFrames& frames,
                             const Eigen::VectorXd& v_mm, Eigen::VectorXd& y_n, int threads) {
  const auto element_product = [&](int64_t t, Eigen::Matrix<double, 3, 4>& f) {
    const TetElement& element = elements[t];
    const Eigen::Matrix<double, 3, 4> v = GatherCorners(element, v_mm);
    // K_e 0 = 0: a sparse v (the predictor's handle jump) touches few
    // elements.
    if (v.isZero(0.0)) return false;
    f = ApplyElementTangent(element, frames.rotations[t], frames.Twist(t), v, frames.Barrier(t));
    return true;
  };
  SumOverElements(elements, v_mm.size(), threads, element_product, y_n);
}

double CorotatedEnergy(const std::vector<TetElement>& elements,
                       const std::vector<Eigen::Matrix3d>& rotations, const Eigen::VectorXd& u_mm,
                       bool inversion_barrier) {
  double energy = 0.0;
  for (size_t t = 0; t < elements.size(); ++t) {
    const TetElement& element = elements[t];
    const Eigen::Matrix3d g = DisplacementGradient(element, GatherCorners(element, u_mm));
    const Eigen::Matrix3d h = CorotatedStrainSource(rotations[t], g);
    const Eigen::Matrix3d eps = 0.5 * (h + h.transpose());
    energy += element.volume_mm3 * (element.mu_n_per_mm2 * eps.squaredNorm() +
                                    0.5 * element.lambda_n_per_mm2 * eps.trace() * eps.trace());
    if (inversion_barrier) {
      energy += EvaluateBarrier(element, Eigen::Matrix3d::Identity() + g).energy_n_mm;
    }
  }
  return energy;
}

}  // namespace vpm

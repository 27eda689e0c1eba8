#include "server/fem/inversion_barrier.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace vpm {
namespace {

double Det(const Eigen::Matrix3d& f) { return f.col(0).dot(f.col(1).cross(f.col(2))); }

}  // namespace

BarrierTerm EvaluateBarrier(const TetElement& element, const Eigen::Matrix3d& f) {
  BarrierTerm term;
  const double j = Det(f);
  constexpr double j0 = kBarrierOnsetVolumeRatio;
  if (!(j > 0.0 && j < j0)) return term;
  const double k = element.lambda_n_per_mm2 + 2.0 * element.mu_n_per_mm2;
  const double d = j - j0;             // < 0
  const double ln = std::log(j / j0);  // < 0
  term.active = true;
  term.cofactor.col(0) = f.col(1).cross(f.col(2));
  term.cofactor.col(1) = f.col(2).cross(f.col(0));
  term.cofactor.col(2) = f.col(0).cross(f.col(1));
  term.energy_n_mm = element.volume_mm3 * k * (-d * d * ln);
  term.stress_scale_n_per_mm2 = k * (-2.0 * d * ln - d * d / j);
  term.curvature_n_per_mm2 = k * (-2.0 * ln - 4.0 * d / j + d * d / (j * j));
  return term;
}

Eigen::Matrix<double, 3, 4> BarrierForces(const TetElement& element, const BarrierTerm& term) {
  if (!term.active) return Eigen::Matrix<double, 3, 4>::Zero();
  return StressNodalForces(element, term.stress_scale_n_per_mm2 * term.cofactor);
}

Eigen::Matrix<double, 3, 4> ApplyBarrierTangent(const TetElement& element, const BarrierTerm& term,
                                                const Eigen::Matrix<double, 3, 4>& v_mm) {
  if (!term.active) return Eigen::Matrix<double, 3, 4>::Zero();
  const double rate = term.cofactor.cwiseProduct(DisplacementGradient(element, v_mm)).sum();
  return StressNodalForces(element, term.curvature_n_per_mm2 * rate * term.cofactor);
}

double VolumeRatio(const TetElement& element, const Eigen::VectorXd& u_mm) {
  return Det(Eigen::Matrix3d::Identity() +
             DisplacementGradient(element, GatherCorners(element, u_mm)));
}

double FeasibleStepFraction(const std::vector<TetElement>& elements, const Eigen::VectorXd& u_mm,
                            const Eigen::VectorXd& du_mm, double keep, double min_alpha,
                            const std::vector<uint8_t>& skip) {
  // Per watched element: F(u) and dF = grad du, so F(u + alpha du) = F +
  // alpha dF, and the floor its det must keep.
  struct Watched {
    Eigen::Matrix3d f, df;
    double floor;
  };
  // False for elements that do not limit the step: skipped, not moved by
  // du, or already inverted.
  const auto watch = [&](size_t t, Watched& w) {
    if (!skip.empty() && skip[t]) return false;
    const TetElement& element = elements[t];
    const Eigen::Matrix<double, 3, 4> du = GatherCorners(element, du_mm);
    if (du.isZero(0.0)) return false;
    w.f = Eigen::Matrix3d::Identity() + DisplacementGradient(element, GatherCorners(element, u_mm));
    const double j = Det(w.f);
    if (!(j > 0.0)) return false;
    w.df = DisplacementGradient(element, du);
    w.floor = keep * std::min(j, kBarrierOnsetVolumeRatio);
    return true;
  };
  // alpha = 1, the first fraction tried and the common case, in a pass that
  // stores nothing.
  if (min_alpha <= 1.0) {
    bool all_hold = true;
    Watched w;
    for (size_t t = 0; t < elements.size() && all_hold; ++t) {
      if (watch(t, w)) all_hold = Det(w.f + w.df) >= w.floor;
    }
    if (all_hold) return 1.0;
  }
  std::vector<Watched> watched;
  Watched w;
  for (size_t t = 0; t < elements.size(); ++t) {
    if (watch(t, w)) watched.push_back(w);
  }
  for (double alpha = 1.0; alpha >= min_alpha; alpha *= 0.5) {
    const bool ok = std::all_of(watched.begin(), watched.end(), [alpha](const Watched& w) {
      return Det(w.f + alpha * w.df) >= w.floor;
    });
    if (ok) return alpha;
  }
  return 0.0;
}

}  // namespace vpm

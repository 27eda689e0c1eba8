#include "server/fem/projected_pcg.h"

#include <cmath>

namespace vpm {
namespace {

void Project(const std::vector<int32_t>& constrained, Eigen::VectorXd& v) {
  for (int32_t d : constrained) v[d] = 0.0;
}

}  // namespace

PcgStats ProjectedPcg(const LinearMap& apply_a, const LinearMap& precondition,
                      const std::vector<int32_t>& constrained, const Eigen::VectorXd& b,
                      double relative_tolerance, int max_iterations, Eigen::VectorXd& x,
                      Eigen::VectorXd* residual) {
  PcgStats stats;
  x.setZero(b.size());
  Eigen::VectorXd r = b;
  Project(constrained, r);
  const double b_norm = r.norm();
  if (!(b_norm > 0.0)) {
    stats.converged = true;
    if (residual != nullptr) *residual = r;
    return stats;
  }
  Eigen::VectorXd z, q;
  precondition(r, z);
  Project(constrained, z);
  Eigen::VectorXd p = z;
  double rz = r.dot(z);
  double r_norm = b_norm;
  while (stats.iterations < max_iterations) {
    apply_a(p, q);
    Project(constrained, q);
    const double pq = p.dot(q);
    if (!(pq > 0.0)) break;  // A not positive definite along p (or NaN)
    const double alpha = rz / pq;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * q;
    ++stats.iterations;
    r_norm = r.norm();
    if (r_norm <= relative_tolerance * b_norm) {
      stats.converged = true;
      break;
    }
    precondition(r, z);
    Project(constrained, z);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  stats.relative_residual = r_norm / b_norm;
  if (residual != nullptr) *residual = std::move(r);
  return stats;
}

}  // namespace vpm

// Preconditioned conjugate gradients restricted to the unconstrained DOFs.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

namespace vpm {

using LinearMap = std::function<void(const Eigen::VectorXd& in, Eigen::VectorXd& out)>;

struct PcgStats {
  int iterations = 0;
  double relative_residual = 0.0;  // |b - A x| / |b| on the free DOFs
  bool converged = false;
};

// Solves A_SS x_S = b_S, S = all DOFs not listed in `constrained`, starting
// from x = 0; x is 0 on the constrained DOFs.
//   apply_a        y = A v (n to n), A symmetric positive definite on S
//   precondition   z = M^-1 r, symmetric positive definite on S, z_C = 0
//   constrained    indices in [0, n)
//   b              n, entries on constrained DOFs are ignored
//   relative_tolerance  stop at |r| <= tol |b| (dimensionless)
// Output: x (n, resized); if residual is not null, the final b - A x
// (n, 0 on the constrained DOFs). Units follow A and b.
PcgStats ProjectedPcg(const LinearMap& apply_a, const LinearMap& precondition,
                      const std::vector<int32_t>& constrained, const Eigen::VectorXd& b,
                      double relative_tolerance, int max_iterations, Eigen::VectorXd& x,
                      Eigen::VectorXd* residual = nullptr);

}  // namespace vpm

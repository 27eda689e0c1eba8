#include "server/fem/polar_rotation.h"

#include <cmath>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

namespace vpm {
namespace {

// Below this det of F / |F|_F^3 * 3^1.5 (1 for a rotation) Newton's iteration
// converges slowly or to the wrong factor, so the SVD takes over.
constexpr double kNewtonMinRelativeDet = 1e-4;
constexpr int kNewtonMaxIterations = 30;

Eigen::Matrix3d RotationBySvd(const Eigen::Matrix3d& f) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& u = svd.matrixU();
  const Eigen::Matrix3d& v = svd.matrixV();
  Eigen::Vector3d d(1.0, 1.0, (u * v.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  return u * d.asDiagonal() * v.transpose();
}

// Transpose of the inverse: cofactor matrix / det.
Eigen::Matrix3d InverseTranspose(const Eigen::Matrix3d& x, double det) {
  Eigen::Matrix3d c;
  c.col(0) = x.col(1).cross(x.col(2));
  c.col(1) = x.col(2).cross(x.col(0));
  c.col(2) = x.col(0).cross(x.col(1));
  return c / det;
}

}  // namespace

Eigen::Matrix3d PolarRotation(const Eigen::Matrix3d& f) {
  const double norm = f.norm();
  if (!std::isfinite(norm) || !(norm > 0.0)) return Eigen::Matrix3d::Identity();
  // Scaled so that a rotation keeps norm sqrt(3) and det 1.
  Eigen::Matrix3d x = f * (std::sqrt(3.0) / norm);
  double det = x.determinant();
  if (!(det > kNewtonMinRelativeDet)) return RotationBySvd(f);
  // X <- (zeta X + X^-T / zeta) / 2 with Higham's Frobenius-norm scaling
  // while far from orthogonal; quadratic convergence near the answer.
  for (int k = 0; k < kNewtonMaxIterations; ++k) {
    const Eigen::Matrix3d inv_t = InverseTranspose(x, det);
    const double change_estimate = (x - inv_t).norm();
    const double zeta =
        change_estimate > 1e-2 ? std::sqrt(std::sqrt(inv_t.squaredNorm() / x.squaredNorm())) : 1.0;
    const Eigen::Matrix3d next = 0.5 * (zeta * x + inv_t / zeta);
    const double step = (next - x).norm();
    x = next;
    // Quadratic convergence: the error after this step is ~step^2 / 2.
    if (step < 1e-8) return x;
    det = x.determinant();
    if (!(det > 0.0)) break;
  }
  return RotationBySvd(f);
}

}  // namespace vpm

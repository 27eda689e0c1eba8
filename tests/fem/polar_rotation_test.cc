// The corotational frame: PolarRotation.
#include "server/fem/polar_rotation.h"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/LU>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::Rotation;

Eigen::Matrix3d RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Rotation(Eigen::Vector3d(n(rng), n(rng), n(rng)), 3.0 * n(rng));
}

Eigen::Matrix3d RandomSpd(std::mt19937& rng, double spread) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Matrix3d q = RandomRotation(rng);
  const Eigen::Vector3d s(std::exp(spread * u(rng)), std::exp(spread * u(rng)),
                          std::exp(spread * u(rng)));
  return q * s.asDiagonal() * q.transpose();
}

void ExpectRotation(const Eigen::Matrix3d& r) {
  EXPECT_LT((r.transpose() * r - Eigen::Matrix3d::Identity()).norm(), 1e-13);
  EXPECT_NEAR(r.determinant(), 1.0, 1e-13);
}

TEST(PolarRotation, RecoversTheRotationOfFEqualsRS) {
  std::mt19937 rng(3);
  for (double scale : {1e-8, 1.0, 1e8}) {
    for (double spread : {0.01, 0.5, 2.0}) {
      for (int n = 0; n < 200; ++n) {
        const Eigen::Matrix3d r = RandomRotation(rng);
        const Eigen::Matrix3d f = scale * r * RandomSpd(rng, spread);
        const Eigen::Matrix3d got = PolarRotation(f);
        ExpectRotation(got);
        EXPECT_LT((got - r).norm(), 1e-11) << "scale " << scale << " spread " << spread;
      }
    }
  }
}

TEST(PolarRotation, InvertedElementsGetTheNearestProperRotation) {
  std::mt19937 rng(5);
  for (int n = 0; n < 200; ++n) {
    Eigen::Matrix3d f = RandomRotation(rng) * RandomSpd(rng, 1.0);
    f.col(n % 3) *= -1.0;  // a reflection: det F < 0
    ASSERT_LT(f.determinant(), 0.0);
    const Eigen::Matrix3d r = PolarRotation(f);
    ExpectRotation(r);
    // R^T F is symmetric, and R maximises tr(R^T F) over rotations: the
    // reflection sits on the smallest singular value.
    const Eigen::Matrix3d s = r.transpose() * f;
    EXPECT_LT((s - s.transpose()).norm(), 1e-10 * f.norm());
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(f);
    const Eigen::Vector3d sv = svd.singularValues();
    EXPECT_NEAR(s.trace(), sv[0] + sv[1] - sv[2], 1e-10 * f.norm());
  }
}

TEST(PolarRotation, DegenerateInputsGiveARotation) {
  EXPECT_EQ(PolarRotation(Eigen::Matrix3d::Zero()), Eigen::Matrix3d::Identity());
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(1, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(PolarRotation(nan), Eigen::Matrix3d::Identity());
  // A flat element (rank 2) and a collapsed one (rank 1).
  Eigen::Matrix3d flat = Eigen::Matrix3d::Identity();
  flat(2, 2) = 0.0;
  ExpectRotation(PolarRotation(flat));
  EXPECT_LT((PolarRotation(flat) - Eigen::Matrix3d::Identity()).norm(), 1e-13);
  Eigen::Matrix3d line = Eigen::Matrix3d::Zero();
  line(0, 0) = 2.0;
  ExpectRotation(PolarRotation(line));
}

}  // namespace
}  // namespace vpm

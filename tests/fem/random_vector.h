// A reproducible right-hand side for the FEM solver tests: n standard normal
// entries from a fixed seed.
#pragma once

#include <cstdint>
#include <random>

#include <Eigen/Core>

namespace vpm::testing {

inline Eigen::VectorXd RandomNormalVector(int64_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd r(n);
  for (int64_t i = 0; i < n; ++i) r[i] = g(rng);
  return r;
}

}  // namespace vpm::testing

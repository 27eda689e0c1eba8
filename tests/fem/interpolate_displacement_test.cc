// Displacement anywhere through the rest mesh.
#include "server/fem/interpolate_displacement.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::RandomBoxMesh;
using testing::RestPositions;

TEST(InterpolateDisplacement, IsExactForAffineFieldsAndAtVertices) {
  const glm::dvec3 extent(20.0, 10.0, 15.0);
  const ProxyMesh mesh = RandomBoxMesh(60, 4, extent, 2);
  const auto rest = RestPositions(mesh);
  const glm::dmat3 a(0.1, -0.2, 0.05, 0.3, 0.0, -0.1, 0.02, 0.04, 0.2);
  const glm::dvec3 b(1.0, -2.0, 0.5);
  std::vector<glm::dvec3> u;
  for (const auto& p : rest) u.push_back(a * p + b);
  auto locator = TetLocator::Create(rest, mesh.tets);
  ASSERT_TRUE(locator.ok());
  for (size_t v = 0; v < rest.size(); ++v) {
    EXPECT_LT(glm::distance(*InterpolateDisplacement(*locator, u, rest[v]), u[v]), 1e-12);
  }
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> r(0.0, 1.0);
  std::vector<glm::dvec3> points;
  for (int n = 0; n < 500; ++n) points.push_back(glm::dvec3(r(rng), r(rng), r(rng)) * extent);
  points.push_back(glm::dvec3(-1.0, 5.0, 5.0));  // outside
  auto all = InterpolateDisplacements(*locator, u, points);
  ASSERT_TRUE(all.ok());
  for (size_t n = 0; n + 1 < points.size(); ++n) {
    EXPECT_LT(glm::distance((*all)[n], a * points[n] + b), 1e-12) << n;
  }
  EXPECT_TRUE(std::isnan(all->back().x));
  EXPECT_FALSE(InterpolateDisplacement(*locator, u, points.back()).has_value());
  u.pop_back();
  EXPECT_EQ(InterpolateDisplacements(*locator, u, points).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

// Point location in a tet mesh.
#include "server/mesh/tet_locator.h"

#include <random>

#include <gtest/gtest.h>

#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm {
namespace {

using testing::Positions;
using testing::RandomMesh;

// The smallest tet index whose weights are all >= -eps, by brute force.
int32_t BruteForce(const TetLocator& locator, const glm::dvec3& p, double eps) {
  for (size_t t = 0; t < locator.tets().size(); ++t) {
    const auto w = locator.Barycentric(static_cast<int32_t>(t), p);
    if (w[0] >= -eps && w[1] >= -eps && w[2] >= -eps && w[3] >= -eps)
      return static_cast<int32_t>(t);
  }
  return -1;
}

TEST(TetLocator, FindsTheContainingTetOfRandomPoints) {
  for (double scale : {1e-6, 1.0, 1e6}) {
    SCOPED_TRACE(scale);
    const glm::dvec3 extent = glm::dvec3(40.0, 30.0, 20.0) * scale;
    ProxyMesh mesh = RandomMesh(300, extent, 5);
    ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
    auto locator = TetLocator::Create(Positions(mesh), mesh.tets);
    ASSERT_TRUE(locator.ok()) << locator.status();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int n = 0; n < 2000; ++n) {
      const glm::dvec3 p = glm::dvec3(u(rng), u(rng), u(rng)) * extent;
      const auto hit = locator->Locate(p);
      ASSERT_TRUE(hit.has_value());
      EXPECT_EQ(hit->tet, BruteForce(*locator, p, 1e-9));
      glm::dvec3 back(0.0);
      double sum = 0.0;
      for (int c = 0; c < 4; ++c) {
        EXPECT_GE(hit->weights[c], -1e-9);
        back += hit->weights[c] * mesh.vertices[mesh.tets[hit->tet][c]].position_mm;
        sum += hit->weights[c];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
      EXPECT_NEAR(glm::distance(back, p), 0.0, 1e-12 * scale * 50.0);
    }
  }
}

TEST(TetLocator, SharedVerticesAndFacesGoToTheSmallestTet) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = RandomMesh(50, extent, 9);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  auto locator = TetLocator::Create(Positions(mesh), mesh.tets);
  ASSERT_TRUE(locator.ok());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    int32_t smallest = -1;
    for (size_t t = 0; t < mesh.tets.size() && smallest < 0; ++t) {
      for (int32_t x : mesh.tets[t]) {
        if (x == static_cast<int32_t>(v)) smallest = static_cast<int32_t>(t);
      }
    }
    const auto hit = locator->Locate(mesh.vertices[v].position_mm);
    ASSERT_TRUE(hit.has_value()) << v;
    EXPECT_EQ(hit->tet, smallest) << v;
  }
  // The centroid of each interior face of tet 0 belongs to tet 0.
  const auto& t = mesh.tets[0];
  for (int skip = 0; skip < 4; ++skip) {
    glm::dvec3 centroid(0.0);
    for (int c = 0; c < 4; ++c) {
      if (c != skip) centroid += mesh.vertices[t[c]].position_mm / 3.0;
    }
    EXPECT_EQ(locator->Locate(centroid)->tet, 0);
  }
}

TEST(TetLocator, PointsOutsideTheMeshAreNotFound) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = RandomMesh(50, extent, 9);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  auto locator = TetLocator::Create(Positions(mesh), mesh.tets);
  ASSERT_TRUE(locator.ok());
  EXPECT_FALSE(locator->Locate({-0.1, 5, 5}).has_value());
  EXPECT_FALSE(locator->Locate({5, 5, 10.001}).has_value());
  EXPECT_FALSE(locator->Locate({1e9, 5, 5}).has_value());
  EXPECT_TRUE(locator->Locate({0, 0, 0}).has_value());
  EXPECT_TRUE(locator->Locate({10, 10, 10}).has_value());
}

TEST(TetLocator, RejectsIndicesOutOfRange) {
  auto locator = TetLocator::Create({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2, 3}});
  EXPECT_EQ(locator.status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

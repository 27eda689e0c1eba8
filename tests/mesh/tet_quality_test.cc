// Tet shape measures and the inverted-tet count.
#include "server/mesh/tet_quality.h"

#include <cmath>

#include <gtest/gtest.h>

namespace vpm {
namespace {

const double kRegularDihedralDeg = std::acos(1.0 / 3.0) * 180.0 / M_PI;  // 70.5288

// A regular tet (edge 2 sqrt 2) with positive orientation.
std::array<glm::dvec3, 4> RegularTet(double scale) {
  std::array<glm::dvec3, 4> p = {glm::dvec3(1, 1, 1), glm::dvec3(1, -1, -1), glm::dvec3(-1, 1, -1),
                                 glm::dvec3(-1, -1, 1)};
  for (auto& x : p) x *= scale;
  if (SignedVolume(p[0], p[1], p[2], p[3]) < 0) std::swap(p[2], p[3]);
  return p;
}

TEST(TetQuality, RegularTetHas70Point53DegreesAndRatioOne) {
  EXPECT_NEAR(kRegularDihedralDeg, 70.53, 0.005);
  for (double scale : {1e-6, 1.0, 1e6}) {
    SCOPED_TRACE(scale);
    const auto p = RegularTet(scale);
    EXPECT_NEAR(MinDihedralAngleDeg(p[0], p[1], p[2], p[3]), kRegularDihedralDeg, 1e-9);
    EXPECT_NEAR(RadiusRatio(p[0], p[1], p[2], p[3]), 1.0, 1e-12);
  }
}

TEST(TetQuality, CornerTetOfACube) {
  // (0,0,0),(1,0,0),(0,1,0),(0,0,1): dihedral angles 90 (x3) and
  // acos(1/sqrt 3) = 54.74 (x3); r = 1/(3+sqrt 3), R = sqrt(3)/2.
  const glm::dvec3 o(0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  EXPECT_DOUBLE_EQ(SignedVolume(o, x, y, z), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(SignedVolume(o, y, x, z), -1.0 / 6.0);
  EXPECT_NEAR(MinDihedralAngleDeg(o, x, y, z), std::acos(1.0 / std::sqrt(3.0)) * 180.0 / M_PI,
              1e-9);
  const double expected = 3.0 * (1.0 / (3.0 + std::sqrt(3.0))) / (std::sqrt(3.0) / 2.0);
  EXPECT_NEAR(RadiusRatio(o, x, y, z), expected, 1e-12);
}

TEST(TetQuality, FlatAndInvertedTetsScoreZero) {
  const glm::dvec3 o(0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  const glm::dvec3 in_plane(1, 1, 0);
  EXPECT_EQ(SignedVolume(o, x, y, in_plane), 0.0);
  EXPECT_EQ(RadiusRatio(o, x, y, in_plane), 0.0);
  EXPECT_NEAR(MinDihedralAngleDeg(o, x, y, in_plane), 0.0, 1e-9);
  EXPECT_EQ(RadiusRatio(o, y, x, z), 0.0);  // inverted
}

TEST(TetQuality, MeasureTetQualityTakesMinAndMean) {
  ProxyMesh mesh;
  const auto regular = RegularTet(1.0);
  for (const auto& p : regular) mesh.vertices.push_back(MeshVertex{p});
  mesh.vertices.push_back(MeshVertex{glm::dvec3(0, 0, 0)});
  mesh.vertices.push_back(MeshVertex{glm::dvec3(1, 0, 0)});
  mesh.vertices.push_back(MeshVertex{glm::dvec3(0, 1, 0)});
  mesh.vertices.push_back(MeshVertex{glm::dvec3(0, 0, 1)});
  mesh.tets = {{0, 1, 2, 3}, {4, 5, 6, 7}};
  const TetQuality q = MeasureTetQuality(mesh);
  const double corner_dihedral = std::acos(1.0 / std::sqrt(3.0)) * 180.0 / M_PI;
  EXPECT_NEAR(q.min_dihedral_deg, corner_dihedral, 1e-9);
  EXPECT_NEAR(q.mean_min_dihedral_deg, 0.5 * (corner_dihedral + kRegularDihedralDeg), 1e-9);
  EXPECT_NEAR(q.mean_radius_ratio,
              0.5 * (1.0 + RadiusRatio(mesh.vertices[4].position_mm, mesh.vertices[5].position_mm,
                                       mesh.vertices[6].position_mm, mesh.vertices[7].position_mm)),
              1e-12);
  EXPECT_EQ(q.removed_zero_volume, 0);
  EXPECT_EQ(MeasureTetQuality(ProxyMesh{}).min_dihedral_deg, 0.0);
}

TEST(TetQuality, CountInvertedTetsCountsFlippedAndFlat) {
  const std::vector<glm::dvec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}};
  const std::vector<std::array<int32_t, 4>> tets = {
      {0, 1, 2, 3},  // positive
      {0, 2, 1, 3},  // inverted
      {0, 1, 2, 4},  // flat
  };
  EXPECT_EQ(CountInvertedTets(p, tets), 2);
}

}  // namespace
}  // namespace vpm

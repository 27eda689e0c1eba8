// The proxy mesh between physical voxel space and world LPS
// (server/mesh/mesh_frame.h): an exact round trip, and tets that keep a
// positive signed volume in both frames, also for a reflecting direction.
#include "server/mesh/mesh_frame.h"

#include <cmath>

#include <gtest/gtest.h>

#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm {
namespace {

double SignedVolume(const ProxyMesh& mesh, const std::array<int32_t, 4>& t) {
  const glm::dvec3 a = mesh.vertices[t[0]].position_mm;
  return glm::dot(glm::cross(mesh.vertices[t[1]].position_mm - a,
                             mesh.vertices[t[2]].position_mm - a),
                  mesh.vertices[t[3]].position_mm - a) / 6.0;
}

void ExpectRoundTrip(const VolumeGeometry& geometry) {
  const glm::dvec3 extent(20.0, 10.0, 5.0);
  ProxyMesh mesh = testing::LatticeMesh(3, extent);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  for (const auto& t : mesh.tets) ASSERT_GT(SignedVolume(mesh, t), 0.0);

  const ProxyMesh world = MeshToWorld(mesh, geometry);
  ASSERT_EQ(world.vertices.size(), mesh.vertices.size());
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const glm::dvec3 expected = geometry.PhysicalToWorld(mesh.vertices[v].position_mm);
    EXPECT_NEAR(glm::distance(world.vertices[v].position_mm, expected), 0.0, 1e-9);
  }
  for (const auto& t : world.tets) EXPECT_GT(SignedVolume(world, t), 0.0);

  const ProxyMesh back = MeshFromWorld(world, geometry);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    EXPECT_NEAR(glm::distance(back.vertices[v].position_mm, mesh.vertices[v].position_mm), 0.0,
                1e-9);
  }
  EXPECT_EQ(back.tets, mesh.tets);
}

TEST(MeshFrame, RotationRoundTripsAndKeepsTetsPositive) {
  VolumeGeometry g;
  g.origin_mm = {-123.5, -55.5, 755.7};
  const double c = std::cos(0.3229), s = std::sin(0.3229);  // an 18.5 degree gantry tilt
  g.direction = glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, c, -s), glm::dvec3(0, s, c));
  ExpectRoundTrip(g);
}

TEST(MeshFrame, ReflectionSwapsTwoCornersSoTetsStayPositive) {
  VolumeGeometry g;
  g.origin_mm = {178.0, -11.3, 94.3};
  // det = -1: the i axis right-to-left only (some scanners' files).
  g.direction = glm::dmat3(glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1));
  ExpectRoundTrip(g);
}

}  // namespace
}  // namespace vpm

// Boundary vertices (boundary_vertices.h): on the faces, fine where vertices
// come close to a face, none where nothing does, and what they buy.
#include "server/mesh/boundary_vertices.h"

#include <gtest/gtest.h>

#include "server/mesh/build_proxy_mesh.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

VolumeGeometry Box(double mm) {
  VolumeGeometry g;
  g.dims = {101, 101, 101};
  g.spacing_mm = glm::dvec3(mm / 100.0);
  return g;
}

TEST(BoundaryVertices, NoneWhenNothingComesNearAFace) {
  const VolumeGeometry g = Box(100.0);
  std::vector<MeshVertex> vertices = MakeAnchors(g);
  vertices.push_back({.position_mm = glm::dvec3(50.0)});
  // The centre is at least 50 mm from every face: depth_ratio 6 * 50 mm is
  // wider than any face (100 mm): no split at all.
  EXPECT_TRUE(BoundaryVertices(vertices, g, {}).empty());
}

TEST(BoundaryVertices, ShallowVertexGetsFineFaceCellsOnItsFaceOnly) {
  const VolumeGeometry g = Box(100.0);
  std::vector<MeshVertex> vertices = MakeAnchors(g);
  vertices.push_back({.position_mm = glm::dvec3(50.0, 50.0, 2.0)});  // 2 mm above z = 0
  const std::vector<MeshVertex> boundary = BoundaryVertices(vertices, g, {.min_cell_mm = 1.0});
  ASSERT_FALSE(boundary.empty());
  double nearest = 1e9;
  for (const MeshVertex& b : boundary) {
    EXPECT_EQ(b.kind, VertexKind::kBoundary);
    EXPECT_EQ(b.lattice_id, -1);
    int on_faces = 0;
    for (int a = 0; a < 3; ++a) {
      on_faces += b.position_mm[a] == 0.0 || b.position_mm[a] == 100.0;
    }
    EXPECT_GE(on_faces, 1);
    nearest = std::min(nearest, glm::distance(b.position_mm, glm::dvec3(50.0, 50.0, 0.0)));
  }
  // Cells near the vertex are at most about depth_ratio * its distance wide.
  EXPECT_LE(nearest, 6.0 * 2.0);
}

TEST(BuildProxyMesh, BoundaryVerticesAndFlipsLeaveNoTetUnderFiveDegreesAtTheBox) {
  const Volume volume = testing::MakeBodyVolume();
  MeshParams params;
  params.grid = {12, 10, 8};
  params.target = 100;
  auto mesh = BuildProxyMesh(volume, params);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_GT(mesh->stats.boundary, 0);
  EXPECT_GE(mesh->quality.min_dihedral_deg, 5.0);
}

}  // namespace
}  // namespace vpm

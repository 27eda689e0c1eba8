// Steiner points against slivers (sliver_steiner_points.h): they lift the
// smallest dihedral angle to the target without moving a vertex, on a
// hand-made sliver and on the meshes vpm builds (docs/MESH.md, "Tet quality").
#include "server/mesh/sliver_steiner_points.h"

#include <gtest/gtest.h>

#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

VolumeGeometry Box100() {
  VolumeGeometry g;
  g.dims = {101, 101, 101};
  g.spacing_mm = glm::dvec3(1.0);
  return g;
}

// The anchors and a tight cluster of four vertices 4 mm apart in the middle
// of the 100 mm box, as a refinement cluster among distant step-2 vertices:
// every triangulation has wedges between the cluster and the corners (two
// close and two far vertices), which no flip mends.
ProxyMesh SliverMesh(const VolumeGeometry& g) {
  ProxyMesh mesh;
  mesh.vertices = MakeAnchors(g);
  for (const glm::dvec3& p : {glm::dvec3(50, 50, 50), glm::dvec3(54, 50, 50.5),
                              glm::dvec3(50, 54, 49.5), glm::dvec3(51, 51, 54)}) {
    mesh.vertices.push_back({.position_mm = p});
  }
  return mesh;
}

TEST(SliverSteinerPoints, LiftTheSmallestAngleWithoutMovingAVertex) {
  const VolumeGeometry g = Box100();
  ProxyMesh mesh = SliverMesh(g);
  ASSERT_TRUE(Tetrahedralize(mesh, g.extent_mm()).ok());
  ASSERT_LT(mesh.quality.min_dihedral_deg, 5.0) << "the input must hold a sliver";
  const std::vector<MeshVertex> before = mesh.vertices;
  auto stats = AddSliverSteinerPoints(mesh, g, {.min_spacing_mm = 2.0});
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_GE(mesh.quality.min_dihedral_deg, 5.0);
  EXPECT_DOUBLE_EQ(stats->min_dihedral_after_deg, mesh.quality.min_dihedral_deg);
  EXPECT_LT(stats->min_dihedral_before_deg, 5.0);
  ASSERT_EQ(mesh.vertices.size(), before.size() + static_cast<size_t>(stats->added));
  EXPECT_GT(stats->added, 0);
  for (size_t v = 0; v < before.size(); ++v) {
    EXPECT_EQ(mesh.vertices[v].position_mm, before[v].position_mm) << "vertex " << v;
  }
  for (size_t v = before.size(); v < mesh.vertices.size(); ++v) {
    const MeshVertex& s = mesh.vertices[v];
    EXPECT_EQ(s.kind, VertexKind::kSteiner);
    EXPECT_EQ(s.lattice_id, -1);
    for (int a = 0; a < 3; ++a) {
      EXPECT_GE(s.position_mm[a], 0.0);
      EXPECT_LE(s.position_mm[a], 100.0);
    }
    for (size_t u = 0; u < v; ++u) {
      EXPECT_GE(glm::distance(s.position_mm, mesh.vertices[u].position_mm), 2.0);
    }
  }
}

TEST(SliverSteinerPoints, RejectNonPositiveParams) {
  const VolumeGeometry g = Box100();
  ProxyMesh mesh = SliverMesh(g);
  ASSERT_TRUE(Tetrahedralize(mesh, g.extent_mm()).ok());
  EXPECT_EQ(AddSliverSteinerPoints(mesh, g, {.min_spacing_mm = 0.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(AddSliverSteinerPoints(mesh, g, {.target_min_dihedral_deg = -1.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// Meshes refined at a point, as the server builds them, on the synthetic
// body (the phantom, the MRI and the CT: tests/measures/drag_validity_test.cc):
// every tet at 5 degrees or more, and the vertices of the mesh without
// Steiner points kept, in order, at the same positions.
TEST(SliverSteinerPoints, RefinedMeshesHaveNoTetUnderFiveDegreesAndKeepTheirVertices) {
  const Volume volume = testing::MakeBodyVolume({90, 75, 60});
  for (Footprint footprint : {Footprint::kPoint, Footprint::kCell}) {
    SCOPED_TRACE(FootprintName(footprint));
    MeshParams params;
    params.footprint = footprint;
    params.refine_at_mm = volume.geometry().extent_mm() * glm::dvec3(0.6, 0.5, 0.5);
    // The sliver points alone (the hard-reach ones come before them and
    // count in stats.steiner too).
    params.hard_reach_factor = 0.0;
    auto mesh = BuildProxyMesh(volume, params);
    ASSERT_TRUE(mesh.ok()) << mesh.status();
    params.steiner_min_dihedral_deg = 0.0;
    auto plain = BuildProxyMesh(volume, params);
    ASSERT_TRUE(plain.ok()) << plain.status();
    EXPECT_LT(plain->quality.min_dihedral_deg, 5.0) << "flips alone already reach 5 degrees";
    EXPECT_GE(mesh->quality.min_dihedral_deg, 5.0);
    EXPECT_GT(mesh->stats.steiner, 0);
    EXPECT_EQ(mesh->stats.steiner, static_cast<int64_t>(mesh->vertices.size() -
                                                        plain->vertices.size()));
    for (size_t v = 0; v < plain->vertices.size(); ++v) {
      EXPECT_EQ(mesh->vertices[v].position_mm, plain->vertices[v].position_mm);
      EXPECT_EQ(mesh->vertices[v].kind, plain->vertices[v].kind);
    }
  }
}

}  // namespace
}  // namespace vpm

// Steiner points on long hard edges (hard_reach_steiner_points.h): near the
// given point no edge from a hard vertex to a soft one stays longer than the
// reach, no vertex moves, and the new vertices are classified (docs/MESH.md,
// "Hard tets: Steiner points").
#include "server/mesh/hard_reach_steiner_points.h"

#include <gtest/gtest.h>

#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/steiner_point.h"
#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/steiner_vertex_checks.h"

namespace vpm {
namespace {

using testing::ExpectSteinerVertex;

// A 100 mm box (2 mm voxels) of soft tissue (40) under a bone slab (700)
// at z >= 90 mm, with one voxel of air (-1000 HU) at the origin: CT in HU
// (ct_in_hu.h), so that bone is hard.
Volume SlabVolume() {
  VolumeGeometry g;
  g.dims = {51, 51, 51};
  g.spacing_mm = glm::dvec3(2.0);
  std::vector<float> values(g.voxel_count());
  for (int64_t k = 0; k < g.dims[2]; ++k) {
    for (int64_t i = 0; i < g.dims[0] * g.dims[1]; ++i) {
      values[i + g.dims[0] * g.dims[1] * k] = 2.0 * k >= 90.0 ? 700.0f : 40.0f;
    }
  }
  values[0] = -1000.0f;
  return *Volume::Create(g, std::move(values));
}

// The anchors, a 3 x 3 grid of vertices in the bone and a cluster of soft
// ones 40 mm under it: Delaunay joins the bone to the cluster directly, as it
// joined the skull to the brain near the grab on the tilted head CT.
ProxyMesh SlabMesh(const Volume& volume) {
  ProxyMesh mesh;
  mesh.vertices = MakeAnchors(volume.geometry());
  for (double x : {20.0, 50.0, 80.0}) {
    for (double y : {20.0, 50.0, 80.0}) {
      const glm::dvec3 p(x, y, 95.0);
      mesh.vertices.push_back({.position_mm = p, .voxel = NearestVoxel(volume.geometry(), p)});
    }
  }
  for (double dx : {-5.0, 5.0}) {
    for (double dy : {-5.0, 5.0}) {
      for (double dz : {-5.0, 5.0}) {
        const glm::dvec3 p = glm::dvec3(50.0, 50.0, 50.0) + glm::dvec3(dx, dy, dz);
        mesh.vertices.push_back({.position_mm = p, .voxel = NearestVoxel(volume.geometry(), p)});
      }
    }
  }
  return mesh;
}

// The longest edge from a hard vertex to a soft one within radius_mm of
// center_mm, mm.
double LongestHardEdgeNear(const ProxyMesh& mesh, const glm::dvec3& center_mm, double radius_mm) {
  double longest = 0.0;
  for (const auto& tet : mesh.tets) {
    for (int32_t a : tet) {
      for (int32_t b : tet) {
        const MeshVertex& hard = mesh.vertices[a];
        const MeshVertex& soft = mesh.vertices[b];
        if (!hard.hard || soft.hard) continue;
        if (glm::distance(soft.position_mm, center_mm) > radius_mm) continue;
        longest = std::max(longest, glm::distance(hard.position_mm, soft.position_mm));
      }
    }
  }
  return longest;
}

constexpr double kR = 10.0;  // step 2's density radius, mm (for the influence rule)

TEST(HardReachSteinerPoints, ShortenEveryHardEdgeNearThePointWithoutMovingAVertex) {
  const Volume volume = SlabVolume();
  ProxyMesh mesh = SlabMesh(volume);
  ASSERT_TRUE(Tetrahedralize(mesh, volume.geometry().extent_mm()).ok());
  ASSERT_TRUE(ClassifyHardness(volume, kR, {}, mesh.vertices).ok());
  const HardReachParams params{.max_reach_mm = 15.0,
                               .center_mm = {50.0, 50.0, 50.0},
                               .radius_mm = 30.0,
                               .min_spacing_mm = 2.0};
  ASSERT_GT(LongestHardEdgeNear(mesh, params.center_mm, params.radius_mm), 30.0)
      << "the input must join the bone to the cluster";
  const std::vector<MeshVertex> before = mesh.vertices;
  auto stats = AddHardReachSteinerPoints(mesh, volume, kR, {}, params);
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_GT(stats->longest_before_mm, 30.0);
  EXPECT_LE(LongestHardEdgeNear(mesh, params.center_mm, params.radius_mm), 15.0 + 1e-9);
  ASSERT_EQ(mesh.vertices.size(), before.size() + static_cast<size_t>(stats->added));
  EXPECT_GT(stats->added, 0);
  for (size_t v = 0; v < before.size(); ++v) {
    EXPECT_EQ(mesh.vertices[v].position_mm, before[v].position_mm) << "vertex " << v;
    EXPECT_EQ(mesh.vertices[v].hard, before[v].hard) << "vertex " << v;
  }
  std::vector<MeshVertex> reclassified = mesh.vertices;
  ASSERT_TRUE(ClassifyHardness(volume, kR, {}, reclassified).ok());
  for (size_t v = before.size(); v < mesh.vertices.size(); ++v) {
    ExpectSteinerVertex(mesh, v, 100.0, 2.0);
    EXPECT_EQ(mesh.vertices[v].hard, reclassified[v].hard) << "vertex " << v << " is not classified";
  }
}

// Far from the point nothing is added: the hard tets there are section 5's.
TEST(HardReachSteinerPoints, AddNothingWhereNoSoftVertexIsNearThePoint) {
  const Volume volume = SlabVolume();
  ProxyMesh mesh = SlabMesh(volume);
  ASSERT_TRUE(Tetrahedralize(mesh, volume.geometry().extent_mm()).ok());
  const size_t count = mesh.vertices.size();
  // Around (50, 50, 5): only anchors there, and they are 45 mm or more away.
  auto stats = AddHardReachSteinerPoints(
      mesh, volume, kR, {},
      {.max_reach_mm = 15.0, .center_mm = {50.0, 50.0, 5.0}, .radius_mm = 20.0});
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_EQ(stats->added, 0);
  EXPECT_EQ(mesh.vertices.size(), count);
}

TEST(HardReachSteinerPoints, RejectNonPositiveParams) {
  const Volume volume = SlabVolume();
  ProxyMesh mesh = SlabMesh(volume);
  ASSERT_TRUE(Tetrahedralize(mesh, volume.geometry().extent_mm()).ok());
  EXPECT_EQ(AddHardReachSteinerPoints(mesh, volume, kR, {}, {.max_reach_mm = 0.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(AddHardReachSteinerPoints(mesh, volume, kR, {},
                                      {.max_reach_mm = 15.0, .min_spacing_mm = -1.0})
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

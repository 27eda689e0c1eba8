// Section-5 constraints: anchors and hard vertices fixed, face vertices slide.
#include "server/fem/fixed_dofs.h"

#include <gtest/gtest.h>

#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::GridMesh;

TEST(FixedDofs, CornersFixedFacesSlideInteriorFree) {
  for (double scale : {1e-3, 1.0, 1e3}) {
    const glm::dvec3 extent = glm::dvec3(4.0, 5.0, 6.0) * scale;
    ProxyMesh mesh = GridMesh({2, 2, 2}, extent);  // 27 vertices
    mesh.vertices[13].hard = false;                // the centre
    auto fixed = FixedDofs(mesh, extent);
    ASSERT_TRUE(fixed.ok()) << fixed.status();
    int per_count[4] = {0, 0, 0, 0};
    for (size_t v = 0; v < mesh.vertices.size(); ++v) {
      const int n = (*fixed)[3 * v] + (*fixed)[3 * v + 1] + (*fixed)[3 * v + 2];
      ++per_count[n];
      const glm::dvec3 p = mesh.vertices[v].position_mm;
      for (int i = 0; i < 3; ++i) {
        const bool on_face = p[i] == 0.0 || p[i] == extent[i];
        EXPECT_EQ((*fixed)[3 * v + i], on_face ? 1 : 0) << v << " axis " << i;
      }
    }
    EXPECT_EQ(per_count[0], 1);   // centre
    EXPECT_EQ(per_count[1], 6);   // face centres
    EXPECT_EQ(per_count[2], 12);  // edge midpoints
    EXPECT_EQ(per_count[3], 8);   // corners
  }
}

TEST(FixedDofs, HardVerticesAndAnchorsAreFixedEverywhere) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = GridMesh({2, 2, 2}, extent);
  mesh.vertices[13].hard = mesh.vertices[13].skeleton = true;
  // Within 1e-6 relative of a face counts as on it; 1e-5 does not.
  mesh.vertices[4].position_mm.z = 1e-7 * extent.z;
  mesh.vertices[22].position_mm.z = extent.z * (1.0 - 1e-5);
  MeshVertex anchor;
  anchor.kind = VertexKind::kAnchor;
  anchor.position_mm = glm::dvec3(3.0, 4.0, 5.0);
  mesh.vertices.push_back(anchor);
  const auto fixed = *FixedDofs(mesh, extent);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(fixed[3 * 13 + i], 1);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(fixed[3 * 27 + i], 1);
  EXPECT_EQ(fixed[3 * 4 + 2], 1);
  EXPECT_EQ(fixed[3 * 22 + 2], 0);
}

TEST(FixedDofs, RejectsBadExtentAndPositions) {
  ProxyMesh mesh = GridMesh({1, 1, 1}, glm::dvec3(1.0));
  EXPECT_EQ(FixedDofs(mesh, glm::dvec3(1.0, 0.0, 1.0)).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(FixedDofs(mesh, glm::dvec3(1.0, 1.0, std::nan(""))).status().code(),
            absl::StatusCode::kInvalidArgument);
  mesh.vertices[0].position_mm.x = std::nan("");
  EXPECT_EQ(FixedDofs(mesh, glm::dvec3(1.0)).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

// What every Steiner vertex must be, for the Steiner steps' tests
// (sliver_steiner_points_test.cc, hard_reach_steiner_points_test.cc).
#pragma once

#include <cstddef>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include "server/mesh/proxy_mesh.h"

namespace vpm::testing {

// Vertex v of `mesh` is a Steiner vertex (no lattice id) inside the box
// [0, box_mm]^3 and at least min_spacing_mm from every vertex before it.
inline void ExpectSteinerVertex(const ProxyMesh& mesh, size_t v, double box_mm,
                                double min_spacing_mm) {
  const MeshVertex& s = mesh.vertices[v];
  EXPECT_EQ(s.kind, VertexKind::kSteiner) << "vertex " << v;
  EXPECT_EQ(s.lattice_id, -1) << "vertex " << v;
  for (int a = 0; a < 3; ++a) {
    EXPECT_GE(s.position_mm[a], 0.0) << "vertex " << v;
    EXPECT_LE(s.position_mm[a], box_mm) << "vertex " << v;
  }
  for (size_t u = 0; u < v; ++u) {
    EXPECT_GE(glm::distance(s.position_mm, mesh.vertices[u].position_mm), min_spacing_mm)
        << "vertices " << u << " and " << v;
  }
}

}  // namespace vpm::testing

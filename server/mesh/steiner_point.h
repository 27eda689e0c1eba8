// Placing a Steiner point (sliver_steiner_points.h, hard_reach_steiner_points.h):
// into the box, away from the vertices there are, on its voxel.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "server/mesh/lattice.h"  // NearestVoxel
#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

// Distance from p to the nearest of points (infinity for none), mm.
inline double NearestDistance(const std::vector<glm::dvec3>& points, const glm::dvec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const glm::dvec3& q : points) best = std::min(best, glm::distance(p, q));
  return best;
}

// `p` clamped into the box [0, extent], then put on any face it lies within
// `snap` of (mm): a vertex in a thin layer under a face makes flat tets with
// the vertices on that face.
inline glm::dvec3 SnapToBox(const glm::dvec3& p, const glm::dvec3& extent, double snap) {
  glm::dvec3 q = glm::clamp(p, glm::dvec3(0.0), extent);
  for (int a = 0; a < 3; ++a) {
    if (q[a] < snap) q[a] = 0.0;
    if (q[a] > extent[a] - snap) q[a] = extent[a];
  }
  return q;
}

// Appends a Steiner vertex (no lattice id, on its nearest voxel) at each of
// `points` (mm); the caller tetrahedralizes again.
inline void AppendSteinerVertices(ProxyMesh& mesh, const VolumeGeometry& geometry,
                                  const std::vector<glm::dvec3>& points) {
  for (const glm::dvec3& q : points) {
    mesh.vertices.push_back({.position_mm = q,
                             .lattice_id = -1,
                             .kind = VertexKind::kSteiner,
                             .voxel = NearestVoxel(geometry, q)});
  }
}

}  // namespace vpm

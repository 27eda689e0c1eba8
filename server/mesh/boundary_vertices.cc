#include "server/mesh/boundary_vertices.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>

namespace vpm {
namespace {

struct FacePoint {
  double u, v, depth;  // mm: in-face coordinates and distance to the face
};

struct Face {
  int axis;       // normal axis
  double at_mm;   // 0 or the extent along it
  int u_axis, v_axis;
};

// Splits the cell [u0, u1] x [v0, v1] while it is too wide for the points
// above it, collecting leaf corners (in-face coordinates).
void Subdivide(const std::vector<FacePoint>& points, const BoundaryParams& params, double u0,
               double u1, double v0, double v1, std::set<std::array<double, 2>>& corners) {
  const double width = std::max(u1 - u0, v1 - v0);
  const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
  double distance = std::numeric_limits<double>::infinity();
  for (const FacePoint& p : points) {
    distance = std::min(distance, std::hypot(p.u - uc, p.v - vc, p.depth));
  }
  if (width > params.depth_ratio * distance && width / 2.0 >= params.min_cell_mm) {
    const double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
    Subdivide(points, params, u0, um, v0, vm, corners);
    Subdivide(points, params, um, u1, v0, vm, corners);
    Subdivide(points, params, u0, um, vm, v1, corners);
    Subdivide(points, params, um, u1, vm, v1, corners);
    return;
  }
  for (double u : {u0, u1}) {
    for (double v : {v0, v1}) corners.insert({u, v});
  }
}

}  // namespace

std::vector<MeshVertex> BoundaryVertices(const std::vector<MeshVertex>& vertices,
                                         const VolumeGeometry& geometry,
                                         const BoundaryParams& params) {
  const glm::dvec3 extent = geometry.extent_mm();
  std::set<std::array<double, 3>> taken;
  for (const MeshVertex& v : vertices) taken.insert({v.position_mm.x, v.position_mm.y, v.position_mm.z});
  std::vector<MeshVertex> out;
  for (int axis = 0; axis < 3; ++axis) {
    for (double at : {0.0, extent[axis]}) {
      const Face face{axis, at, (axis + 1) % 3, (axis + 2) % 3};
      std::vector<FacePoint> points;
      for (const MeshVertex& v : vertices) {
        const glm::dvec3& p = v.position_mm;
        points.push_back({p[face.u_axis], p[face.v_axis], std::abs(p[axis] - at)});
      }
      // The corners themselves are at depth 0 of their faces: they must not
      // drive the split.
      std::erase_if(points, [](const FacePoint& p) { return p.depth == 0.0; });
      std::set<std::array<double, 2>> corners;
      Subdivide(points, params, 0.0, extent[face.u_axis], 0.0, extent[face.v_axis], corners);
      for (const auto& [u, v] : corners) {
        glm::dvec3 p;
        p[axis] = at;
        p[face.u_axis] = u;
        p[face.v_axis] = v;
        if (!taken.insert({p.x, p.y, p.z}).second) continue;
        MeshVertex b{.position_mm = p, .lattice_id = -1, .kind = VertexKind::kBoundary};
        for (int a = 0; a < 3; ++a) {
          const double index = std::floor(p[a] / geometry.spacing_mm[a] + 0.5);
          b.voxel[a] = std::clamp<int64_t>(static_cast<int64_t>(index), 0, geometry.dims[a] - 1);
        }
        out.push_back(b);
      }
    }
  }
  return out;
}

}  // namespace vpm

// Meshes and helpers for the FEM tests.
#pragma once

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <glm/glm.hpp>

#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/proxy_mesh.h"
#include "server/mesh/tet_quality.h"
#include "server/mesh/tetrahedralize.h"

namespace vpm::testing {

// A structured mesh of the box [0, extent]: (cells+1)^3 grid vertices, each
// hex split into 6 tets around its main diagonal (conforming, positive
// orientation). The 8 corners are anchors, the rest lattice vertices.
inline ProxyMesh GridMesh(std::array<int, 3> cells, const glm::dvec3& extent) {
  ProxyMesh mesh;
  const int nx = cells[0] + 1, ny = cells[1] + 1, nz = cells[2] + 1;
  auto id = [&](int i, int j, int k) { return static_cast<int32_t>(i + nx * (j + ny * k)); };
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        MeshVertex v;
        v.position_mm = glm::dvec3(i, j, k) / glm::dvec3(cells[0], cells[1], cells[2]) * extent;
        const bool corner =
            (i == 0 || i == nx - 1) && (j == 0 || j == ny - 1) && (k == 0 || k == nz - 1);
        v.kind = corner ? VertexKind::kAnchor : VertexKind::kLattice;
        mesh.vertices.push_back(v);
      }
    }
  }
  const std::array<std::array<int, 3>, 6> orders = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (int k = 0; k < cells[2]; ++k) {
    for (int j = 0; j < cells[1]; ++j) {
      for (int i = 0; i < cells[0]; ++i) {
        for (const auto& order : orders) {
          std::array<int, 3> c = {i, j, k};
          std::array<int32_t, 4> tet;
          tet[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[order[s]];
            tet[s + 1] = id(c[0], c[1], c[2]);
          }
          const auto& p = mesh.vertices;
          if (SignedVolume(p[tet[0]].position_mm, p[tet[1]].position_mm, p[tet[2]].position_mm,
                           p[tet[3]].position_mm) < 0.0) {
            std::swap(tet[2], tet[3]);
          }
          mesh.tets.push_back(tet);
        }
      }
    }
  }
  return mesh;
}

// Delaunay mesh of the box [0, extent]: the 8 corners (anchors), `per_face`
// random points on each of the 6 faces and `interior` random points inside.
inline ProxyMesh RandomBoxMesh(int interior, int per_face, const glm::dvec3& extent,
                               uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  ProxyMesh mesh;
  for (int c = 0; c < 8; ++c) {
    MeshVertex v;
    v.position_mm = glm::dvec3(c & 1 ? 1.0 : 0.0, c & 2 ? 1.0 : 0.0, c & 4 ? 1.0 : 0.0) * extent;
    v.kind = VertexKind::kAnchor;
    mesh.vertices.push_back(v);
  }
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      for (int n = 0; n < per_face; ++n) {
        MeshVertex v;
        glm::dvec3 q(u(rng), u(rng), u(rng));
        q[axis] = side;
        v.position_mm = q * extent;
        mesh.vertices.push_back(v);
      }
    }
  }
  for (int n = 0; n < interior; ++n) {
    MeshVertex v;
    v.position_mm = glm::dvec3(u(rng), u(rng), u(rng)) * extent;
    mesh.vertices.push_back(v);
  }
  if (!Tetrahedralize(mesh, extent).ok()) mesh.tets.clear();
  return mesh;
}

// The proxy mesh of a volume (10^3 lattice to 200 vertices) refined with 40
// vertices at the centre of its box, the grab point of the validity tests.
inline Result<ProxyMesh> CentreRefinedMesh(const Volume& volume) {
  MeshParams params;
  params.grid = {10, 10, 10};
  params.target = 200;
  params.refine_at_mm = volume.geometry().extent_mm() * 0.5;
  params.refine_count = 40;
  return BuildProxyMesh(volume, params);
}

inline std::vector<glm::dvec3> RestPositions(const ProxyMesh& mesh) {
  std::vector<glm::dvec3> p;
  for (const MeshVertex& v : mesh.vertices) p.push_back(v.position_mm);
  return p;
}

// Vertex v of a 3*#V vector.
inline glm::dvec3 At(const Eigen::VectorXd& u, size_t v) {
  return glm::dvec3(u[3 * v], u[3 * v + 1], u[3 * v + 2]);
}

// True when p lies on the surface of the box [0, extent].
inline bool OnBoxSurface(const glm::dvec3& p, const glm::dvec3& extent) {
  for (int i = 0; i < 3; ++i) {
    const double tol = 1e-9 * extent[i];
    if (std::abs(p[i]) <= tol || std::abs(p[i] - extent[i]) <= tol) return true;
  }
  return false;
}

// Rotation by angle_rad about a unit axis, as an Eigen matrix.
inline Eigen::Matrix3d Rotation(const Eigen::Vector3d& axis, double angle_rad) {
  const Eigen::Vector3d n = axis.normalized();
  Eigen::Matrix3d k;
  k << 0, -n.z(), n.y(), n.z(), 0, -n.x(), -n.y(), n.x(), 0;
  return Eigen::Matrix3d::Identity() + std::sin(angle_rad) * k + (1 - std::cos(angle_rad)) * k * k;
}

}  // namespace vpm::testing

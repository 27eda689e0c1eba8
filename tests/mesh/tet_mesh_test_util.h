// Meshes and volumes for the mesh, measures and warp tests.
#pragma once

#include <functional>
#include <random>
#include <vector>

#include <glm/glm.hpp>

#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm::testing {

// The 8 corners of the box [0, extent] as anchors.
inline void AddAnchors(ProxyMesh& mesh, const glm::dvec3& extent) {
  for (int c = 0; c < 8; ++c) {
    MeshVertex v;
    v.position_mm =
        glm::dvec3(c & 1 ? extent.x : 0.0, c & 2 ? extent.y : 0.0, c & 4 ? extent.z : 0.0);
    v.kind = VertexKind::kAnchor;
    mesh.vertices.push_back(v);
  }
}

// A full g^3 lattice at the cell centres of [0, extent] (cells extent/g),
// then the 8 anchors; `keep(a, b, c)` may drop lattice vertices.
inline ProxyMesh LatticeMesh(int g, const glm::dvec3& extent,
                             const std::function<bool(int, int, int)>& keep = nullptr) {
  ProxyMesh mesh;
  for (int c = 0; c < g; ++c) {
    for (int b = 0; b < g; ++b) {
      for (int a = 0; a < g; ++a) {
        if (keep && !keep(a, b, c)) continue;
        MeshVertex v;
        v.position_mm = glm::dvec3(a + 0.5, b + 0.5, c + 0.5) / static_cast<double>(g) * extent;
        v.lattice_id = a + g * (b + g * c);
        v.cost = 0.01 * v.lattice_id;
        mesh.vertices.push_back(v);
      }
    }
  }
  AddAnchors(mesh, extent);
  return mesh;
}

// `count` uniformly random lattice-kind vertices in the box, then the anchors.
inline ProxyMesh RandomMesh(int count, const glm::dvec3& extent, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ProxyMesh mesh;
  for (int n = 0; n < count; ++n) {
    MeshVertex v;
    v.position_mm = glm::dvec3(u(rng), u(rng), u(rng)) * extent;
    v.lattice_id = n;
    mesh.vertices.push_back(v);
  }
  AddAnchors(mesh, extent);
  return mesh;
}

// A volume with value(i, j, k) at each voxel (indices, not mm).
inline Volume MakeVolume(std::array<int64_t, 3> dims, glm::dvec3 spacing_mm,
                         const std::function<float(int64_t, int64_t, int64_t)>& value) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = spacing_mm;
  std::vector<float> values(static_cast<size_t>(g.voxel_count()));
  size_t n = 0;
  for (int64_t k = 0; k < dims[2]; ++k) {
    for (int64_t j = 0; j < dims[1]; ++j) {
      for (int64_t i = 0; i < dims[0]; ++i) values[n++] = value(i, j, k);
    }
  }
  return *Volume::Create(g, std::move(values));
}

inline std::vector<glm::dvec3> Positions(const ProxyMesh& mesh) {
  std::vector<glm::dvec3> p;
  for (const MeshVertex& v : mesh.vertices) p.push_back(v.position_mm);
  return p;
}

}  // namespace vpm::testing

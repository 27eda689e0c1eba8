// Meshes, deformations and volumes for the warp tests.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <glm/glm.hpp>

#include "server/mesh/tetrahedralize.h"
#include "server/volume/volume.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm::testing {

// A tetrahedralized mesh of an image box: rest positions and tets.
struct WarpMesh {
  std::vector<glm::dvec3> rest_mm;
  std::vector<std::array<int32_t, 4>> tets;
  std::vector<char> anchor;  // per vertex: a corner of the box
};

inline WarpMesh Tetrahedralized(ProxyMesh mesh, const glm::dvec3& extent_mm) {
  if (!Tetrahedralize(mesh, extent_mm).ok()) std::abort();
  WarpMesh out;
  out.rest_mm = Positions(mesh);
  out.tets = mesh.tets;
  for (const MeshVertex& v : mesh.vertices) out.anchor.push_back(v.kind == VertexKind::kAnchor);
  return out;
}

// `count` random interior vertices plus the 8 corners of [0, extent].
inline WarpMesh RandomWarpMesh(int count, const glm::dvec3& extent_mm, uint32_t seed) {
  return Tetrahedralized(RandomMesh(count, extent_mm, seed), extent_mm);
}

// A full g^3 lattice of cell centres plus the corners.
inline WarpMesh LatticeWarpMesh(int g, const glm::dvec3& extent_mm) {
  return Tetrahedralized(LatticeMesh(g, extent_mm), extent_mm);
}

// Every non-anchor vertex moved by a uniform random vector in
// [-amplitude, amplitude]^3 (mm).
inline std::vector<glm::dvec3> RandomlyMoved(const WarpMesh& mesh, double amplitude_mm,
                                             uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<glm::dvec3> deformed = mesh.rest_mm;
  for (size_t v = 0; v < deformed.size(); ++v) {
    const glm::dvec3 d(u(rng), u(rng), u(rng));
    if (!mesh.anchor[v]) deformed[v] += amplitude_mm * d;
  }
  return deformed;
}

// A smooth local drag: vertices within radius of centre move by
// offset * (1 - r^2/radius^2)^2; the others stay.
inline std::vector<glm::dvec3> Dragged(const WarpMesh& mesh, const glm::dvec3& centre_mm,
                                       double radius_mm, const glm::dvec3& offset_mm) {
  std::vector<glm::dvec3> deformed = mesh.rest_mm;
  for (size_t v = 0; v < deformed.size(); ++v) {
    const glm::dvec3 d = mesh.rest_mm[v] - centre_mm;
    const double q = glm::dot(d, d) / (radius_mm * radius_mm);
    if (q < 1.0 && !mesh.anchor[v]) deformed[v] += offset_mm * (1.0 - q) * (1.0 - q);
  }
  return deformed;
}

// A volume whose value is linear in the physical position: I = c + g . p.
inline Volume LinearVolume(std::array<int64_t, 3> dims, glm::dvec3 spacing_mm, double c,
                           const glm::dvec3& g) {
  return MakeVolume(dims, spacing_mm, [&](int64_t i, int64_t j, int64_t k) {
    return static_cast<float>(c + glm::dot(g, glm::dvec3(i, j, k) * spacing_mm));
  });
}

}  // namespace vpm::testing

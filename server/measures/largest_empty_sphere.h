// Section 6 "Spread": the largest sphere free of mesh vertices whose centre
// lies inside the body (TF > 0) and inside the image box.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

struct EmptySphere {
  double radius_mm = 0.0;         // distance from centre_mm to the nearest vertex
  glm::dvec3 centre_mm{0.0};      // physical voxel space
  bool centre_is_sample = false;  // the winner is a voxel sample, not a circumcentre
  int64_t circumcentres_in_body = 0;
  int64_t samples_in_body = 0;
};

struct LargestEmptySphereOptions {
  // 0: circumcentres only. s > 0: also every s-th voxel centre per axis (the
  // last index always included) with TF > 0, which catches spheres whose
  // centre sits on the body's or box's boundary, to within s voxels.
  int voxel_stride = 0;
};

// The empty-sphere radius at x, r(x) = distance from x to the nearest mesh
// vertex, maximised over the body B = {x in box : TF(I(x)) > 0} (I sampled
// trilinearly). r is maximised over B either at a Voronoi vertex inside B,
// i.e. a Delaunay tet's circumcentre, or on the boundary of B. This function
// evaluates r exactly (nearest-vertex search, not trusting the Delaunay
// property) at every tet circumcentre inside B, so it is exact when the
// maximum is interior and a lower bound otherwise; voxel_stride > 0 adds
// voxel-centre samples of B that bound the boundary case within
// voxel_stride * |spacing| * sqrt(3) / 2 (r is 1-Lipschitz).
//
// Inputs:
//   mesh    vertices (mm) and tets (Delaunay, as Tetrahedralize leaves them)
//   volume  defines the box [0, extent_mm] and, with tf, the body
// Output: the largest sphere; radius 0 and counts 0 when no candidate lies
// in the body. Ties: the first candidate (tets in order, then voxels in
// index order).
Result<EmptySphere> LargestEmptySphere(const ProxyMesh& mesh, const Volume& volume,
                                       const TransferFunction& tf,
                                       const LargestEmptySphereOptions& options);
inline Result<EmptySphere> LargestEmptySphere(const ProxyMesh& mesh, const Volume& volume,
                                              const TransferFunction& tf) {
  return LargestEmptySphere(mesh, volume, tf, LargestEmptySphereOptions{});
}

}  // namespace vpm

// The section-6 comparison of meshes of one vertex budget: a regular lattice
// against the optimized mesh in each density mode and footprint.
#pragma once

#include <string>
#include <vector>

#include "server/common/status.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/measures/largest_empty_sphere.h"
#include "server/measures/reconstruction_error.h"

namespace vpm {

struct MeshComparisonRow {
  std::string name;             // "regular", "cell/spread", ...
  bool is_default = false;      // the default configuration (MeshParams{}: cell, spread)
  int64_t vertices = 0;          // all, the boundary ones included
  int64_t boundary_vertices = 0;  // on the box faces, beyond the budget
  int64_t steiner_vertices = 0;   // against slivers, beyond the budget
  int64_t tets = 0;
  ReconstructionError reconstruction;
  EmptySphere largest_empty_sphere;  // the spread measure, inside the body
  TetQuality quality;
  double build_ms = 0.0;
};

// A mesh whose vertices are a regular lattice of at most target - 8 vertices
// (the largest such G with the proportions of the image box) plus the 8
// anchors, and boundary vertices on the faces as BuildProxyMesh adds them.
Result<ProxyMesh> BuildRegularMesh(const Volume& volume, int64_t target);

// Rows: regular, then cell/spread, cell/paper, point/spread, point/paper built
// from `params` (its footprint and density mode are overridden per row; no
// refinement). TF > 0 selects the body, with params.tf.
Result<std::vector<MeshComparisonRow>> CompareMeshes(const Volume& volume, const MeshParams& params,
                                                     const MeshGpu& gpu = {});

}  // namespace vpm

// Step 4 of docs/ALGORITHM.md: refinement around a manipulation point m.
// Candidates are the vertices of a lattice 3x finer than G (no finer than
// the volume's voxels along an axis: a thick-slice stack) inside the ball
// |p - m| <= roi_radius, scored Ci*Cg with the chosen footprint over their
// own (smaller) cells; taken in decreasing score (ties: smaller fine id),
// each accepted only if it is at least h/3 from every vertex already in the
// mesh or accepted; at most refine_count.
//
// Cg of a candidate is g / g_max with g_max the largest g of the coarse
// lattice (step 1); any positive normaliser gives the same order.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

struct RefineParams {
  glm::dvec3 point_mm{0.0};  // m, physical voxel space
  double roi_radius_mm = 0;  // default 1.5 h
  int64_t refine_count = 150;
  Footprint footprint = Footprint::kPoint;
};

// Returns the accepted vertices (kind kRefined, lattice_id -1, cost = Ci*Cg),
// in acceptance order. `existing`: every vertex already in the mesh.
// OUT_OF_RANGE if m is outside the image box.
Result<std::vector<MeshVertex>> RefineAtPoint(const Volume& volume, const Lattice& coarse,
                                              const TransferFunction& tf, double g_max,
                                              const std::vector<MeshVertex>& existing,
                                              const RefineParams& params);

}  // namespace vpm

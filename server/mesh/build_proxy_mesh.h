// The whole proxy-mesh pipeline of docs/ALGORITHM.md sections 1-5, with timings:
// step 1 (GPU when given, else the CPU reference), step 2, step 4 at an
// optional manipulation point, step 3 over the final vertex set, and the
// Delaunay tetrahedralization.
//
// It is split in two so that a session can refine again at a new point
// without redoing steps 1-2: DecimateLattice() then FinishProxyMesh().
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/mesh/classify_hardness.h"
#include "server/mesh/decimate.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "server/mesh/lattice_costs_gpu.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

struct MeshParams {
  std::array<int64_t, 3> grid{20, 20, 20};  // G
  int64_t target = 250;                      // kept vertices, 8 anchors included
  // docs/ALGORITHM.md section 1: point is the default (lower tissue RMSE
  // on three of four volumes measured); cell stays selectable.
  Footprint footprint = Footprint::kPoint;
  DensityMode density_mode = DensityMode::kSpread;
  double wg = 1.0;
  double wd = 0.5;
  double radius_factor = 2.0;                // R = radius_factor * h
  std::string tf = "auto";                   // preset ("auto": by the image) or "v:c,..."
  ClassifyParams classify;
  std::optional<glm::dvec3> refine_at_mm;    // step 4 point, physical voxel space
  double roi_radius_factor = 1.5;            // roi radius = factor * h
  int64_t refine_count = 150;
  // Steiner points until every tet's smallest dihedral angle reaches this,
  // degrees; 0 turns them off (sliver_steiner_points.h, docs/MESH.md).
  double steiner_min_dihedral_deg = 5.0;
  // Steiner points so that no edge from a hard vertex to a soft one within
  // hard_reach_radius_factor * h of refine_at_mm is longer than
  // hard_reach_factor * h (hard_reach_steiner_points.h, docs/MESH.md): tets
  // touching bone are hard, and longer ones held brain tissue near the grab
  // still. 0 turns them off; without refine_at_mm there are none. The
  // radius 2 h is what a handle can reach: grab radius h/2, drag 1.5 h.
  double hard_reach_factor = 2.0;
  double hard_reach_radius_factor = 2.0;
};

// Where step 1 runs; both null means the CPU reference.
struct MeshGpu {
  const GpuVolume* volume = nullptr;
  const LatticeCostsGpu* lattice_costs = nullptr;
};

// Steps 1-2: the decimated lattice plus anchors, ready for steps 3-5.
struct DecimatedLattice {
  Lattice lattice;
  TransferFunction tf;
  LatticeCosts costs;
  double g_max = 0.0;                   // max g over the lattice (chosen footprint)
  std::vector<MeshVertex> vertices;     // 8 anchors, then kept lattice vertices by id
  MeshStats stats;                      // grid, counts, h, R, evaluate_ms, decimate_ms
};

// `cancel` is polled between the steps and inside step 2's removal loop: a
// cancelled build returns its status (Cancelled, DeadlineExceeded, ...)
// within milliseconds.
Result<DecimatedLattice> DecimateLattice(const Volume& volume, const MeshParams& params,
                                         const MeshGpu& gpu = {},
                                         const CancelToken& cancel = {});

// Step 4, the boundary vertices, the tetrahedralization with its Steiner
// points, then step 3 over every vertex, on top of `base`; refine_at_mm of
// `params` (if any) replaces any earlier refinement.
// `cancel` is polled between the steps, between Steiner rounds and inside
// the Delaunay insertion.
Result<ProxyMesh> FinishProxyMesh(const Volume& volume, const DecimatedLattice& base,
                                  const MeshParams& params, const CancelToken& cancel = {});

inline Result<ProxyMesh> BuildProxyMesh(const Volume& volume, const MeshParams& params,
                                        const MeshGpu& gpu = {},
                                        const CancelToken& cancel = {}) {
  ASSIGN_OR_RETURN(DecimatedLattice base, DecimateLattice(volume, params, gpu, cancel));
  return FinishProxyMesh(volume, base, params, cancel);
}

// The 8 corners of the image box, (0,0,0) to (n-1)*s, as anchors.
std::vector<MeshVertex> MakeAnchors(const VolumeGeometry& geometry);

}  // namespace vpm

// Steiner points that remove the tets no flip can mend (docs/MESH.md, "Tet
// quality: Steiner points"; an extension of docs/ALGORITHM.md section 4).
//
// After Delaunay and flips (tetrahedralize.h) the tets left under a few
// degrees are wedges between the refinement cluster (vertices h/3 apart) and
// step-2 vertices 2-4 h away, and a few near the box faces. Their vertices
// are where steps 2-4 put them, so no other triangulation of them is better.
// A new vertex at the bad tet's circumcentre removes it (the point lies in
// its circumsphere, so Delaunay no longer has it) and grades the mesh between
// the close and the far vertices, as Delaunay refinement does (Shewchuk
// 1998); where the circumcentre is too close to a vertex, the centroid is
// tried. Rounds of insertion, each followed by Delaunay and flips again, run
// until every tet reaches the target angle or no candidate is left.
//
// No existing vertex moves: the lattice positions of section 1, the step-4
// and the boundary vertices stay exactly where they are.
#pragma once

#include <cstdint>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

struct SteinerParams {
  // Tets whose smallest dihedral angle is below this get a Steiner point,
  // degrees (issue 16: 5).
  double target_min_dihedral_deg = 5.0;
  // Insertion rounds (each re-tetrahedralizes); stops earlier when every
  // tet reaches the target or no candidate is accepted.
  int max_rounds = 12;
  // A candidate closer than this to any vertex is not taken, mm (> 0):
  // keeps points from piling up where a bad tet cannot be mended.
  double min_spacing_mm = 1.0;
};

struct SteinerStats {
  int rounds = 0;
  int64_t added = 0;
  double min_dihedral_before_deg = 0.0;
  double min_dihedral_after_deg = 0.0;
};

// Adds vertices of kind kSteiner to mesh.vertices (lattice_id -1, cost 0,
// voxel the nearest voxel, not hard: step 3 classifies them with the rest)
// and re-tetrahedralizes (Tetrahedralize, so mesh.tets and mesh.quality are
// those of the final vertex set).
//   mesh      vertices in physical voxel space (mm) with mesh.tets already
//             built by Tetrahedralize over them
//   geometry  the volume's geometry: the box [0, extent_mm()] every new
//             vertex lies in (on a face at worst), and its voxels
// Fails only where Tetrahedralize fails (it cannot on a mesh it built) or
// on non-positive params.
// Returns `cancel`'s status once it cancels (polled each round and inside
// each tetrahedralization).
Result<SteinerStats> AddSliverSteinerPoints(ProxyMesh& mesh, const VolumeGeometry& geometry,
                                            const SteinerParams& params,
                                            const CancelToken& cancel = {});

}  // namespace vpm

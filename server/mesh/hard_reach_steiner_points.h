// Steiner points that keep hard tets short (docs/MESH.md, "Hard tets: Steiner
// points"; an extension of docs/ALGORITHM.md section 4, like the sliver
// Steiner points).
//
// Section 5 makes every tet with a hard vertex hard (E_hard = 1e4 E_soft),
// and hard vertices are fixed. A soft vertex of a hard tet is then held in
// place by the bone: the whole tet barely deforms. Where decimation leaves
// homogeneous tissue sparse (the brain of a head CT), Delaunay joins bone
// vertices to soft ones several lattice steps away, and the hard tets reach
// deep into the soft tissue: on the tilted head CT, tets of 150-1,500 mm^3
// joined the skull to brain vertices 10 mm from the grab point, 45 mm away,
// which then moved 0.02 mm while the handles went 20 mm, and the drag of
// 1.5 h crushed the one layer of tets between them (docs/FEM.md, "Forced
// inversions").
//
// Here every edge from a hard vertex to a non-hard one longer than
// `max_reach_mm` gets a vertex on it, at max_reach_mm from the hard end, in
// rounds (each re-tetrahedralizes and classifies the new points) until no
// such edge is left or no candidate is accepted. Bone stays as rigid as
// section 5 makes it; the tissue it holds is the tissue within max_reach_mm
// of it. No existing vertex moves.
#pragma once

#include <cstdint>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/mesh/classify_hardness.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

struct HardReachParams {
  // Longest edge allowed from a hard vertex to a non-hard one within
  // radius_mm of center_mm, mm (> 0).
  double max_reach_mm = 0.0;
  glm::dvec3 center_mm{0.0};
  double radius_mm = 0.0;
  int max_rounds = 8;
  // A candidate closer than this to any vertex is not taken, mm (> 0).
  double min_spacing_mm = 1.0;
};

struct HardReachStats {
  int rounds = 0;
  int64_t added = 0;
  // The longest edge from a hard vertex to a non-hard one within the
  // radius, before and after, mm.
  double longest_before_mm = 0.0;
  double longest_after_mm = 0.0;
};

// Adds vertices of kind kSteiner on the long hard edges of mesh and
// re-tetrahedralizes; leaves every vertex classified (ClassifyHardness with
// R_mm and classify, step 3).
//   mesh    vertices (mm) with mesh.tets built by Tetrahedralize over them
//   volume  the image: its box bounds the new vertices, its voxels classify
//           them
// Fails where Tetrahedralize or ClassifyHardness fail, or on non-positive
// params; returns `cancel`'s status once it cancels (polled each round).
Result<HardReachStats> AddHardReachSteinerPoints(ProxyMesh& mesh, const Volume& volume, double R_mm,
                                                 const ClassifyParams& classify,
                                                 const HardReachParams& params,
                                                 const CancelToken& cancel = {});

}  // namespace vpm

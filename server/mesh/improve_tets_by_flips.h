// Sliver removal by flips: changes which tets fill the box, never where a
// vertex is (docs/MESH.md, "Tet quality").
//
// A Delaunay tetrahedralization of points taken from a regular lattice is
// full of slivers: four nearly cospherical points (two lattice rows one above
// the other) make a flat tet that Delaunay cannot avoid, however the
// degeneracy is broken. Another triangulation of the same points usually
// can. Local topological operations, each applied only when it raises the
// smallest dihedral angle among the tets it replaces (hill climbing, so the
// mesh's smallest angle never falls):
//   - face flip 2-3: two tets sharing a face become three around the edge
//     joining their apexes;
//   - edge removal n-2(n-2), 3 <= n <= kMaxEdgeRemovalRing: the n tets
//     around an interior edge become the best triangulation of their ring
//     (dynamic programming over the ring's polygon triangulations, Klingner
//     and Shewchuk, "Aggressive tetrahedral mesh improvement", 2007); n = 3
//     is the 3-2 flip, n = 4 the 4-4 flip.
// Boundary faces and edges (on the hull) are never flipped, so the hull, and
// every face on it, stays as it was.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/status.h"

namespace vpm {

// Longest ring of tets around an edge that edge removal tries.
inline constexpr int kMaxEdgeRemovalRing = 16;

struct FlipOptions {
  // Tets whose smallest dihedral angle is below this are worked on, degrees.
  double target_min_dihedral_deg = 10.0;
  // Passes over those tets; stops earlier when a pass changes nothing.
  int max_passes = 10;
};

struct FlipStats {
  int64_t face_flips = 0;     // 2-3
  int64_t edge_removals = 0;  // n-2(n-2), 3-2 and 4-4 included
  int passes = 0;
  double min_dihedral_before_deg = 0.0;
  double min_dihedral_after_deg = 0.0;
};

// Improves `tets` in place by flips.
//   positions  #V by 3, mm (any consistent unit)
//   tets       #T by 4 indices into positions, each with positive signed
//              volume, forming a conforming tetrahedralization (every
//              interior face shared by exactly two tets); on return, the
//              same with each tet's smallest dihedral angle among the tets
//              it came from raised, in no particular order
// The covered region and its boundary faces are unchanged.
// `cancel` is polled at each pass and every 256 tets worked on; once it
// cancels, `tets` is left as it came in and its status is returned.
Result<FlipStats> ImproveTetsByFlips(const std::vector<glm::dvec3>& positions,
                                     std::vector<std::array<int32_t, 4>>& tets,
                                     const FlipOptions& options, const CancelToken& cancel);

// The same, never cancelled.
inline FlipStats ImproveTetsByFlips(const std::vector<glm::dvec3>& positions,
                                    std::vector<std::array<int32_t, 4>>& tets,
                                    const FlipOptions& options = {}) {
  return *ImproveTetsByFlips(positions, tets, options, CancelToken());
}

}  // namespace vpm

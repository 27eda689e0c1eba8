// Which vertices a grab takes (docs/ALGORITHM.md section 5, "grab(point,
// radius)").
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"

namespace vpm {

// When no deformable vertex lies within the radius, a grab takes this many
// nearest deformable vertices (one tet's worth).
inline constexpr int kNearestHandleCount = 4;

struct GrabInfo {
  std::vector<int32_t> handles;  // vertex indices, ascending
  bool used_nearest = false;     // the radius held no deformable vertex
  int64_t fixed_within = 0;      // fixed vertices (hard, anchors) within the radius: they stay
  int64_t left_free_next_to_fixed = 0;  // deformable, within the radius, next to a fixed
                                        // vertex within it: left free (not the nearest)
  std::string message;           // what happened, for the user
  double setup_ms = 0.0;         // preparing the solver for these handles
};

// Handles for a grab.
//   positions_mm    #V by 3, mm (the current, possibly deformed, positions)
//   deformable      #V flags: 1 if the vertex may be a handle (not hard, not
//                   an anchor, at least one free DOF)
//   fixed_neighbours #V lists: the fixed vertices (hard, anchor: every DOF
//                   fixed) that share a tet with the vertex; empty = none
//   box_extent_mm   3, the image box [0, extent], mm
//   point_mm        3, mm; radius_mm > 0
// Output: the deformable vertices within radius_mm of point_mm (distance <=
// radius) that share no tet with a fixed vertex within the radius, and
// always the nearest
// deformable vertex within the radius (docs/FEM.md, "Manipulation": a
// handle next to a fixed vertex would make their tets wholly prescribed,
// and a drag past the fixed vertex inverts them whatever the solver does);
// the others are counted in left_free_next_to_fixed. If no deformable
// vertex and no vertex at all lies within the radius, the
// kNearestHandleCount nearest deformable vertices (used_nearest = true,
// ties by smaller index).
// Errors: InvalidArgument for a non-finite point or radius <= 0 (or not
// finite), or flags of the wrong length; OutOfRange for a point outside the
// box (1e-6 relative slack); FailedPrecondition when the radius holds only
// fixed vertices, or the mesh has no deformable vertex.
Result<GrabInfo> FindHandles(const std::vector<glm::dvec3>& positions_mm,
                             const std::vector<uint8_t>& deformable,
                             const std::vector<std::vector<int32_t>>& fixed_neighbours,
                             const glm::dvec3& box_extent_mm, const glm::dvec3& point_mm,
                             double radius_mm);

}  // namespace vpm

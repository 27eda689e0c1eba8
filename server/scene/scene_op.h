// One manipulation of a deformable scene as the scene applied it: what a
// case records (server/cases/) and what DeformableScene replays onto a
// refined mesh or a reopened case. Physical voxel space, mm.
#pragma once

#include <glm/glm.hpp>

namespace vpm {

// Which tissue a grab takes (docs/FEM.md, "The organ grab").
enum class GrabRule {
  kOrgan,  // the tissue connected to the point (organ_region.h), within a bound
  kBall,   // the paper's ball: deformable vertices within the radius (FindHandles)
};

struct GrabRequest {
  glm::dvec3 point_mm{0.0};  // physical voxel space, mm
  GrabRule rule = GrabRule::kOrgan;
  // kBall: the ball's radius; kOrgan: the region's bound (max distance from
  // the point). 0: the rule's default (kBall: one lattice step h; kOrgan:
  // OrganRegionParams::max_radius_mm). mm, finite, >= 0.
  double radius_mm = 0.0;
};

struct SceneOp {
  // kSettle: a still frame finished the bounded drag events here
  // (DeformableScene::Settle); a case marks the event before it
  // (CaseEvent::settled), so that a replay takes the same path.
  // kRemesh: the session's mesh was replaced here by one refined at
  // `vector` (refinement on grab): the scene was rebuilt on it from its
  // folded history. The scene itself changes nothing for it; a session's
  // replay rebuilds there (Session::ReplaySceneLocked).
  enum class Kind { kGrab, kDrag, kPull, kRelease, kPin, kReset, kSettle, kRemesh };
  Kind kind = Kind::kGrab;
  GrabRequest grab;        // kGrab
  glm::dvec3 vector{0.0};  // kDrag: offset mm; kPull: force N; kPin, kRemesh: point mm
  double radius_mm = 0.0;  // kPin
  bool keep = false;       // kRelease
};

// True for the ops that begin a user's action: a grab (with the drags and
// the release that follow it), a pin, a reset. Undo takes back one action.
inline bool StartsAction(SceneOp::Kind kind) {
  return kind == SceneOp::Kind::kGrab || kind == SceneOp::Kind::kPin ||
         kind == SceneOp::Kind::kReset;
}

}  // namespace vpm

// What holds the tissue now, folded from the ops applied since the scene
// was made: the grabs, each with its last drag or pull (drags and pulls are
// absolute), kept releases and pins, in order. A release that does not
// keep drops its grab and its motion; a reset clears everything; a settle
// changes nothing. Replaying ops() on a scene at rest gives the same
// constraints as replaying every op (the same state within the solver's
// tolerance: DeformableScene::Replay).
#pragma once

#include <vector>

#include "server/scene/scene_op.h"

namespace vpm {

class SceneHistory {
 public:
  void Record(const SceneOp& op);
  const std::vector<SceneOp>& ops() const { return ops_; }
  void Clear() { ops_.clear(); }

 private:
  std::vector<SceneOp> ops_;
};

// The folded history of `log` (every op in the order applied).
std::vector<SceneOp> FoldHistory(const std::vector<SceneOp>& log);

// The ops of `log` after its last reset: a scene at rest replaying them
// exactly reaches the state replaying all of `log` reaches.
std::vector<SceneOp> SinceLastReset(const std::vector<SceneOp>& log);

}  // namespace vpm

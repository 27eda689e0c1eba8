#include "server/scene/scene_history.h"

namespace vpm {

void SceneHistory::Record(const SceneOp& op) {
  switch (op.kind) {
    case SceneOp::Kind::kGrab:
    case SceneOp::Kind::kPin:
      ops_.push_back(op);
      return;
    case SceneOp::Kind::kDrag:
    case SceneOp::Kind::kPull:
      // Absolute: a grab's later motion replaces its earlier one.
      if (!ops_.empty() && (ops_.back().kind == SceneOp::Kind::kDrag ||
                            ops_.back().kind == SceneOp::Kind::kPull)) {
        ops_.back() = op;
      } else {
        ops_.push_back(op);
      }
      return;
    case SceneOp::Kind::kRelease:
      if (op.keep) {
        ops_.push_back(op);
        return;
      }
      // Nothing of this grab stays: drop it and its motion.
      while (!ops_.empty() && ops_.back().kind != SceneOp::Kind::kGrab) ops_.pop_back();
      if (!ops_.empty()) ops_.pop_back();
      return;
    case SceneOp::Kind::kReset:
      ops_.clear();
      return;
    case SceneOp::Kind::kSettle:
    case SceneOp::Kind::kRemesh:
      return;  // changes no constraint
  }
}

std::vector<SceneOp> SinceLastReset(const std::vector<SceneOp>& log) {
  size_t from = 0;
  for (size_t i = 0; i < log.size(); ++i) {
    if (log[i].kind == SceneOp::Kind::kReset) from = i + 1;
  }
  return {log.begin() + static_cast<std::ptrdiff_t>(from), log.end()};
}

std::vector<SceneOp> FoldHistory(const std::vector<SceneOp>& log) {
  SceneHistory history;
  for (const SceneOp& op : log) history.Record(op);
  return history.ops();
}

}  // namespace vpm

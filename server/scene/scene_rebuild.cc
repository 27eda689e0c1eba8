// DeformableScene's history and its replay onto a refined mesh
// (docs/SERVICE.md, "Refinement without asking") or a reopened case
// (docs/CASES.md).
#include "server/scene/deformable_scene.h"

namespace vpm {

void DeformableScene::Record(const SceneOp& op) {
  last_op_ = op;
  history_.Record(op);
}

Status DeformableScene::Replay(const std::vector<SceneOp>& ops, ReplayMode mode) {
  const bool folded = mode == ReplayMode::kFolded;
  for (const SceneOp& op : ops) {
    switch (op.kind) {
      case SceneOp::Kind::kGrab:
        RETURN_IF_ERROR(Grab(op.grab).status());
        break;
      case SceneOp::Kind::kDrag:
        RETURN_IF_ERROR(Drag(op.vector).status());
        // A drag event's work is bounded (docs/FEM.md): finish it, as the
        // running scene has (or will by its next still).
        if (folded) RETURN_IF_ERROR(Settle(kSettleSolves).status());
        break;
      case SceneOp::Kind::kPull:
        RETURN_IF_ERROR(Pull(op.vector).status());
        break;
      case SceneOp::Kind::kRelease:
        RETURN_IF_ERROR(Release(op.keep).status());
        if (folded) RETURN_IF_ERROR(Settle(kSettleSolves).status());
        break;
      case SceneOp::Kind::kPin:
        RETURN_IF_ERROR(Pin(op.vector, op.radius_mm).status());
        break;
      case SceneOp::Kind::kReset:
        RETURN_IF_ERROR(Reset().status());
        break;
      case SceneOp::Kind::kSettle:
        RETURN_IF_ERROR(Settle(kSettleSolves).status());
        break;
      case SceneOp::Kind::kRemesh:
        break;  // the mesh is the caller's (Session::ReplaySceneLocked)
    }
  }
  return absl::OkStatus();
}

Result<std::unique_ptr<DeformableScene>> DeformableScene::Replayed(
    const ProxyMesh& mesh, const std::vector<SceneOp>& ops, ReplayMode mode) const {
  ASSIGN_OR_RETURN(std::unique_ptr<DeformableScene> scene,
                   Create(*context_, *volume_, *gpu_volume_, *renderer_, mesh, options_));
  RETURN_IF_ERROR(scene->Replay(ops, mode));
  return scene;
}

Result<std::unique_ptr<DeformableScene>> DeformableScene::Rebuilt(const ProxyMesh& mesh) const {
  return Replayed(mesh, history_.ops(), ReplayMode::kFolded);
}

}  // namespace vpm

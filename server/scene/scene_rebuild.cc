// DeformableScene's history and its replay onto a refined mesh
// (docs/SERVICE.md, "Refinement without asking").
#include "server/scene/deformable_scene.h"

namespace vpm {

void DeformableScene::RecordMotion(SceneOp op) {
  if (!history_.empty() && (history_.back().kind == SceneOp::Kind::kDrag ||
                            history_.back().kind == SceneOp::Kind::kPull)) {
    history_.back() = op;
  } else {
    history_.push_back(op);
  }
}

Result<std::unique_ptr<DeformableScene>> DeformableScene::Rebuilt(const ProxyMesh& mesh) const {
  ASSIGN_OR_RETURN(std::unique_ptr<DeformableScene> scene,
                   Create(*context_, *volume_, *gpu_volume_, *renderer_, mesh, options_));
  for (const SceneOp& op : history_) {
    switch (op.kind) {
      case SceneOp::Kind::kGrab:
        RETURN_IF_ERROR(scene->Grab(op.grab).status());
        break;
      case SceneOp::Kind::kDrag:
        RETURN_IF_ERROR(scene->Drag(op.vector).status());
        // A drag event's work is bounded (docs/FEM.md): finish it, as the
        // running scene has (or will by its next still).
        RETURN_IF_ERROR(scene->Settle(kSettleSolves).status());
        break;
      case SceneOp::Kind::kPull:
        RETURN_IF_ERROR(scene->Pull(op.vector).status());
        break;
      case SceneOp::Kind::kRelease:
        RETURN_IF_ERROR(scene->Release(op.keep).status());
        RETURN_IF_ERROR(scene->Settle(kSettleSolves).status());
        break;
      case SceneOp::Kind::kPin:
        RETURN_IF_ERROR(scene->Pin(op.vector, op.radius_mm).status());
        break;
    }
  }
  return scene;
}

}  // namespace vpm

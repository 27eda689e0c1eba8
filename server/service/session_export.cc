// A session's state as an export takes it (docs/PACS.md, "Export"): the
// settled deformation's volume and a still frame, under the frame and scene
// locks so that both show the same state.
#include "server/scene/scene_history.h"
#include "server/service/session.h"

namespace vpm::service {

Result<Session::Exported> Session::Export(const CancelToken& cancel) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  std::lock_guard frame_lock(frame_mutex_);
  std::lock_guard scene_lock(scene_mutex_);
  SwapInRefinedMeshLocked();
  SceneStepTimings step;
  {
    std::lock_guard lock(state_mutex_);
    step = last_step_;
  }
  RETURN_IF_ERROR(SettleLocked(&step));
  RETURN_IF_ERROR(cancel.Check());
  SceneView last;
  {
    std::lock_guard lock(state_mutex_);
    last = last_view_;
    last.camera = camera_;
  }
  ASSIGN_OR_RETURN(SceneView view, ExportView(last));
  view.quality = RenderQuality::kStill;
  ASSIGN_OR_RETURN(Frame frame, scene_->Render(view));
  RETURN_IF_ERROR(cancel.Check());
  ASSIGN_OR_RETURN(Volume deformed, scene_->WarpedVolume());
  Exported out{.deformed = std::move(deformed),
               .frame = std::move(frame),
               .max_displacement_mm = step.max_displacement_mm};
  for (const SceneOp& op : SinceLastReset(scene_->history())) {
    if (op.kind == SceneOp::Kind::kGrab || op.kind == SceneOp::Kind::kPin) ++out.manipulations;
  }
  if (const auto grabbed = scene_->GrabPointMm()) {
    out.grab_world_mm = volume_->volume.geometry().PhysicalToWorld(*grabbed);
  }
  return out;
}

}  // namespace vpm::service

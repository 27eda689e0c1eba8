// A session's case (docs/CASES.md): each acknowledged manipulation stored,
// the scene replayed from the case on attach, undo, redo and a refused
// write.
#include <chrono>
#include <cstdio>

#include "proto/client_event_kind.h"
#include "server/scene/scene_history.h"
#include "server/service/case_view.h"
#include "server/service/session.h"

namespace vpm::service {

Status Session::AttachCase(cases::CaseStore* store, std::string case_id,
                           const std::vector<SceneOp>& ops, const std::string& camera,
                           const std::string& render_settings) {
  if (!render_settings.empty()) {
    ASSIGN_OR_RETURN(v3::RenderSettings view, ParseCaseView(render_settings, case_id));
    std::lock_guard lock(view_mutex_);
    kept_view_ = std::move(view);
    kept_view_bytes_ = stored_view_bytes_ = render_settings;
  }
  std::lock_guard frame_lock(frame_mutex_);
  std::lock_guard scene_lock(scene_mutex_);
  case_store_ = store;
  case_id_ = std::move(case_id);
  if (!camera.empty()) {
    v3::Camera api;
    if (!api.ParseFromString(camera)) {
      return absl::DataLossError(StrCat("case '", case_id_, "': its stored camera is unreadable"));
    }
    ASSIGN_OR_RETURN(Camera c, ToCamera(api, volume_->volume.geometry()));
    std::lock_guard lock(state_mutex_);
    camera_ = c;
  }
  if (ops.empty()) return absl::OkStatus();
  return ReplaySceneLocked(ops, DeformableScene::ReplayMode::kExact);
}

Status Session::ReplaySceneLocked(const std::vector<SceneOp>& ops,
                                  DeformableScene::ReplayMode mode) {
  std::shared_ptr<const MeshEntry> mesh;
  {
    std::lock_guard lock(state_mutex_);
    mesh = mesh_;
  }
  // After the last swap of a refined mesh (kRemesh), the scene was rebuilt
  // from its folded history (DeformableScene::Rebuilt): the same here, then
  // the ops that followed. The mesh in use is the case's last (SetMeshParams).
  size_t rebuilt_at = ops.size();
  for (size_t i = 0; i < ops.size(); ++i) {
    if (ops[i].kind == SceneOp::Kind::kRemesh) rebuilt_at = i;
  }
  std::unique_ptr<DeformableScene> replayed;
  if (rebuilt_at == ops.size()) {
    ASSIGN_OR_RETURN(replayed, scene_->Replayed(mesh->mesh, ops, mode));
  } else {
    const std::vector<SceneOp> before(ops.begin(), ops.begin() + std::ptrdiff_t(rebuilt_at));
    ASSIGN_OR_RETURN(replayed, scene_->Replayed(mesh->mesh, FoldHistory(before),
                                                DeformableScene::ReplayMode::kFolded));
    const std::vector<SceneOp> after(ops.begin() + std::ptrdiff_t(rebuilt_at) + 1, ops.end());
    RETURN_IF_ERROR(replayed->Replay(after, mode));
  }
  scene_ = std::move(replayed);
  std::lock_guard lock(state_mutex_);
  last_step_ = SceneStepTimings{};
  TakeSceneStateLocked();
  return absl::OkStatus();
}

void Session::TakeSceneStateLocked() {
  last_step_.max_displacement_mm = scene_->fem().MaxDisplacementMm();
  last_step_.inverted_tets = scene_->fem().CountInvertedTets();
  last_step_.lag_mm = scene_->fem().lag_mm();
}

void Session::StoreCameraInCase(const v3::Camera& camera) {
  if (case_store_ == nullptr) return;
  // The camera is part of the case, but a view the store cannot keep is no
  // reason to refuse the view: it is said, not returned.
  if (Status stored = case_store_->SetCamera(case_id_, camera.SerializeAsString()); !stored.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: camera not stored: %s\n", id_.c_str(),
                 stored.ToString().c_str());
  }
}

Result<std::vector<SceneOp>> Session::CaseHistory() const {
  ASSIGN_OR_RETURN(const std::vector<cases::CaseEvent> events, case_store_->Events(case_id_));
  return SinceLastReset(cases::ReplayLog(events));
}

void Session::RecordSettleInCase() {
  if (case_store_ == nullptr) return;
  Status stored = case_store_->MarkSettled(case_id_);
  if (stored.ok()) stored = case_store_->SetDisplacement(case_id_, scene_->fem().MaxDisplacementMm());
  if (!stored.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: a still's settle not stored: %s\n",
                 id_.c_str(), stored.ToString().c_str());
  }
}

Status Session::StoreInCase(const v3::ClientEvent& event, const std::vector<SceneOp>& before,
                            std::unique_lock<std::mutex>& scene_lock) {
  if (case_store_ == nullptr) return absl::OkStatus();
  if (event.has_camera()) {
    StoreCameraInCase(event.camera());
    return absl::OkStatus();
  }
  if (!IsManipulation(event) || !scene_->last_op()) return absl::OkStatus();
  Result<int64_t> stored =
      case_store_->Append(case_id_, *scene_->last_op(), scene_->fem().MaxDisplacementMm());
  if (stored.ok()) return absl::OkStatus();
  // Refused: the scene goes back to what the case holds (or, if the case
  // cannot be read either, to what it held before this event), under the
  // frame lock, as no frame may be cast from a scene being replaced.
  scene_lock.unlock();
  std::lock_guard frame_lock(frame_mutex_);
  scene_lock.lock();
  Result<std::vector<SceneOp>> history = CaseHistory();
  Status replayed =
      history.ok() ? ReplaySceneLocked(*history, DeformableScene::ReplayMode::kExact)
                   : ReplaySceneLocked(before, DeformableScene::ReplayMode::kFolded);
  if (!replayed.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: the scene could not go back to its case: %s\n",
                 id_.c_str(), replayed.ToString().c_str());
  }
  return Status(stored.status().code(),
                StrCat(stored.status().message(), "; this manipulation was not applied"));
}

Result<Session::UndoOutcome> Session::Undo(bool redo) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  if (case_store_ == nullptr) {
    return absl::FailedPreconditionError(
        "undo: this server keeps no cases (start vpm-server with --state-dir DIR)");
  }
  Touch();
  UndoOutcome outcome;
  {
    std::lock_guard frame_lock(frame_mutex_);
    std::lock_guard scene_lock(scene_mutex_);
    ASSIGN_OR_RETURN(outcome.changed, redo ? case_store_->Redo(case_id_)
                                           : case_store_->Undo(case_id_));
    if (outcome.changed) {
      ASSIGN_OR_RETURN(const std::vector<SceneOp> history, CaseHistory());
      RETURN_IF_ERROR(ReplaySceneLocked(history, DeformableScene::ReplayMode::kExact));
      outcome.max_displacement_mm = scene_->fem().MaxDisplacementMm();
      RETURN_IF_ERROR(case_store_->SetDisplacement(case_id_, outcome.max_displacement_mm));
    } else {
      outcome.max_displacement_mm = scene_->fem().MaxDisplacementMm();
    }
  }
  ASSIGN_OR_RETURN(const cases::CaseRecord record, case_store_->Get(case_id_));
  outcome.events = record.events;
  outcome.undone = record.undone;
  if (outcome.changed) Changed(0, true, nullptr);
  return outcome;
}

}  // namespace vpm::service

// Session: refinement without asking (docs/SERVICE.md). A grab where the
// mesh is coarse asks for the mesh refined there, built beside the running
// one; the next frame swaps it in and replays the manipulation onto it.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "server/common/clock.h"
#include "server/service/session.h"

namespace vpm::service {

std::shared_ptr<const MeshEntry> Session::mesh() const {
  std::lock_guard lock(state_mutex_);
  return mesh_;
}

void Session::RefineAtGrab(const glm::dvec3& point_mm) {
  if (!options_.refine) return;
  std::string mesh_id;
  {
    std::lock_guard lock(state_mutex_);
    if (closed_) return;
    const double near_mm = 0.5 * mesh_->mesh.stats.h_mm;
    const std::optional<glm::dvec3>& at = refined_mesh_ ? refined_mesh_->params.refine_at_mm
                                                        : mesh_->params.refine_at_mm;
    if (at && glm::distance(*at, point_mm) <= near_mm) return;
    if (refining_at_) return;  // one at a time: the next grab asks again
    refining_at_ = point_mm;
    mesh_id = mesh_->id;
  }
  options_.refine(weak_from_this(), std::move(mesh_id), point_mm, refine_cancel_.token());
}

void Session::OfferRefinedMesh(Result<std::shared_ptr<const MeshEntry>> refined) {
  {
    std::lock_guard lock(state_mutex_);
    refining_at_.reset();
    if (closed_) return;
    if (!refined.ok()) {
      std::fprintf(stderr, "vpm-server: session %s: refinement at the grab failed: %s\n",
                   id_.c_str(), refined.status().ToString().c_str());
      return;
    }
    refined_mesh_ = *std::move(refined);
  }
  // A frame for every stream: it swaps the finer mesh in.
  Changed(0, false, nullptr);
}

void Session::SwapInRefinedMeshLocked() {
  std::shared_ptr<const MeshEntry> next;
  {
    std::lock_guard lock(state_mutex_);
    next = std::move(refined_mesh_);
    refined_mesh_.reset();
  }
  if (!next) return;
  const auto t0 = std::chrono::steady_clock::now();
  Result<std::unique_ptr<DeformableScene>> rebuilt = scene_->Rebuilt(next->mesh);
  if (!rebuilt.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: the refined mesh was not swapped in: %s\n",
                 id_.c_str(), rebuilt.status().ToString().c_str());
    return;
  }
  scene_ = *std::move(rebuilt);
  RecordRemeshInCase(*next);
  std::lock_guard lock(state_mutex_);
  TakeSceneStateLocked();
  mesh_ = std::move(next);
  ++refinements_;
  last_swap_ms_ = MsSince(t0);
}

void Session::RecordRemeshInCase(const MeshEntry& refined) {
  if (case_store_ == nullptr || !refined.params.refine_at_mm) return;
  // The case reopens on the refined mesh, rebuilt where the swap was.
  Status stored = case_store_->SetMeshParams(
      case_id_, MeshParamsToApi(refined.params, volume_->volume.geometry()).SerializeAsString());
  if (stored.ok()) {
    stored = case_store_
                 ->Append(case_id_,
                          {.kind = SceneOp::Kind::kRemesh, .vector = *refined.params.refine_at_mm},
                          scene_->fem().MaxDisplacementMm())
                 .status();
  }
  if (!stored.ok()) {
    std::fprintf(stderr, "vpm-server: session %s: the refined mesh not stored in its case: %s\n",
                 id_.c_str(), stored.ToString().c_str());
  }
}

int64_t Session::refinements() const {
  std::lock_guard lock(state_mutex_);
  return refinements_;
}

double Session::last_swap_ms() const {
  std::lock_guard lock(state_mutex_);
  return last_swap_ms_;
}

}  // namespace vpm::service

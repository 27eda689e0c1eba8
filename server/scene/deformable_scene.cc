#include "server/scene/deformable_scene.h"

#include <algorithm>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>

#include "server/common/clock.h"
#include "server/common/finite_vec3.h"
#include "server/raycast/overlay.h"
#include "server/scene/organ_grab.h"
#include "server/warp/warp_volume.h"

namespace vpm {
namespace {

// Map versions unique in the process: the renderer keys its cached brick
// occupancy on (map image, version), and a later scene's map may reuse an
// address.
std::atomic<uint64_t> next_map_version{1};

SceneStepTimings FromSolve(const SolveStats& solve, std::chrono::steady_clock::time_point t0) {
  return {.fem_ms = MsSince(t0),
          .max_displacement_mm = solve.max_displacement_mm,
          .lag_mm = solve.spring_lag_mm,
          .converged = solve.converged,
          .solve = solve};
}

}  // namespace

Result<std::unique_ptr<DeformableScene>> DeformableScene::Create(
    const gpu::GpuContext& context, const Volume& volume, GpuVolume& gpu_volume,
    VolumeRenderer& renderer, const ProxyMesh& mesh, const Options& options) {
  std::unique_ptr<DeformableScene> scene(new DeformableScene());
  scene->context_ = &context;
  scene->volume_ = &volume;
  scene->gpu_volume_ = &gpu_volume;
  scene->renderer_ = &renderer;
  scene->options_ = options;
  scene->mesh_ = mesh;
  ASSIGN_OR_RETURN(FemModel fem,
                   FemModel::Create(mesh, volume.geometry().extent_mm(), options.fem));
  scene->fem_.emplace(std::move(fem));
  ASSIGN_OR_RETURN(BackwardMap map, BackwardMap::Create(context, volume.geometry(), options.map));
  scene->map_.emplace(std::move(map));
  scene->map_version_ = next_map_version.fetch_add(1);
  scene->defer_map_update_ = options.defer_map_update;
  return scene;
}

Result<GrabInfo> DeformableScene::Grab(const glm::dvec3& point_mm, double radius_mm) {
  return Grab(GrabRequest{.point_mm = point_mm, .rule = GrabRule::kBall, .radius_mm = radius_mm});
}

Result<GrabInfo> DeformableScene::Grab(const GrabRequest& request) {
  if (!IsFinite(request.point_mm)) return absl::InvalidArgumentError("grab point must be finite");
  if (!std::isfinite(request.radius_mm) || request.radius_mm < 0.0) {
    return absl::InvalidArgumentError("grab radius must be finite and >= 0 mm (0: the default)");
  }
  // A grab takes the tissue where it rests: the earlier drag is finished
  // first, so that what the grab holds (and so the state it leads to) does
  // not depend on how far the bounded drag events had come (docs/CASES.md:
  // a case replays to the same state).
  RETURN_IF_ERROR(Settle(kSettleSolves).status());
  GrabInfo info;
  if (request.rule == GrabRule::kBall) {
    const double radius = request.radius_mm > 0.0 ? request.radius_mm : mesh_.stats.h_mm;
    ASSIGN_OR_RETURN(info, fem_->Grab(request.point_mm, radius));
  } else {
    ASSIGN_OR_RETURN(info, GrabOrgan(*volume_, *fem_, request.point_mm, request.radius_mm,
                                     kOrganMarginH * mesh_.stats.h_mm));
  }
  grab_point_mm_ = request.point_mm;
  drag_offset_mm_ = glm::dvec3(0.0);
  Record({.kind = SceneOp::Kind::kGrab, .grab = request});
  return info;
}

Result<SceneStepTimings> DeformableScene::Pin(const glm::dvec3& point_mm, double radius_mm) {
  if (!IsFinite(point_mm)) return absl::InvalidArgumentError("pin point must be finite");
  if (!std::isfinite(radius_mm) || radius_mm < 0.0) {
    return absl::InvalidArgumentError("pin radius must be finite and >= 0 mm (0: h / 2)");
  }
  RETURN_IF_ERROR(Settle(kSettleSolves).status());  // as Grab: pins where the tissue rests
  const double radius = radius_mm > 0.0 ? radius_mm : 0.5 * mesh_.stats.h_mm;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<glm::dvec3> now = fem_->Positions();
  std::vector<int32_t> vertices;
  int32_t nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < now.size(); ++v) {
    if (!fem_->deformable()[v]) continue;
    const double d = glm::distance(now[v], point_mm);
    if (d <= radius) vertices.push_back(static_cast<int32_t>(v));
    if (d < best) best = d, nearest = static_cast<int32_t>(v);
  }
  if (vertices.empty() && nearest >= 0) vertices.push_back(nearest);
  RETURN_IF_ERROR(fem_->Pin(vertices));
  Record({.kind = SceneOp::Kind::kPin, .vector = point_mm, .radius_mm = radius_mm});
  return AfterStep({.fem_ms = MsSince(t0)});
}

Result<SceneStepTimings> DeformableScene::Reset() {
  const auto t0 = std::chrono::steady_clock::now();
  fem_->Reset();
  Record({.kind = SceneOp::Kind::kReset});
  grab_point_mm_.reset();
  drag_offset_mm_ = glm::dvec3(0.0);
  return AfterStep({.fem_ms = MsSince(t0)});
}

Result<SceneStepTimings> DeformableScene::UpdateMap(SceneStepTimings timings) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<glm::dvec3> deformed = fem_->Positions();
  const uint64_t previous_version = map_version_;
  map_version_ = 0;  // unknown until the update has succeeded
  map_previous_version_ = 0;
  ASSIGN_OR_RETURN(BackwardMap::UpdateStats stats,
                   map_->Update(fem_->rest_positions_mm(), deformed, fem_->tets()));
  map_version_ = next_map_version.fetch_add(1);
  map_previous_version_ = previous_version;
  map_changed_ = stats.changed;
  const std::vector<glm::dvec3> u = fem_->Displacements();
  map_identity_ = std::all_of(u.begin(), u.end(),
                              [](const glm::dvec3& d) { return d == glm::dvec3(0.0); });
  timings.warp_ms = MsSince(t0);
  timings.map_gpu_ms = stats.gpu_ms;
  timings.map_copy_ms = stats.copy_ms;
  timings.map_passes = stats.passes;
  timings.moved_tets = stats.moved_tets;
  timings.processed_tets = stats.processed_tets;
  return timings;
}

Result<SceneStepTimings> DeformableScene::AfterStep(SceneStepTimings timings) {
  timings.inverted_tets = fem_->CountInvertedTets();
  // The state's, whatever the step (a pin or a reset solves nothing).
  timings.max_displacement_mm = fem_->MaxDisplacementMm();
  if (!defer_map_update_) return UpdateMap(timings);
  map_stale_ = true;
  return timings;
}

Result<SceneStepTimings> DeformableScene::SyncMap() {
  if (!map_stale_) return SceneStepTimings{};
  ASSIGN_OR_RETURN(SceneStepTimings timings, UpdateMap({}));
  map_stale_ = false;
  return timings;
}

Result<SceneStepTimings> DeformableScene::Drag(const glm::dvec3& offset_mm) {
  const auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(SolveStats solve, fem_->Drag(offset_mm));
  drag_offset_mm_ = offset_mm;
  Record({.kind = SceneOp::Kind::kDrag, .vector = offset_mm});
  return AfterStep(FromSolve(solve, t0));
}

Result<SceneStepTimings> DeformableScene::Pull(const glm::dvec3& force_n) {
  const auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(SolveStats solve, fem_->Pull(force_n));
  Record({.kind = SceneOp::Kind::kPull, .vector = force_n});
  const SceneStepTimings timings = FromSolve(solve, t0);
  // The arrow follows the mean handle displacement.
  glm::dvec3 mean(0.0);
  const auto u = fem_->Displacements();
  for (int32_t h : fem_->grab().handles) mean += u[h];
  if (!fem_->grab().handles.empty()) mean /= double(fem_->grab().handles.size());
  drag_offset_mm_ = mean;
  return AfterStep(timings);
}

Result<SceneStepTimings> DeformableScene::Settle(int max_solves) {
  if (fem_->settled()) return SceneStepTimings{};
  const auto t0 = std::chrono::steady_clock::now();
  SolveStats last;
  for (int i = 0; i < max_solves && !fem_->settled(); ++i) {
    ASSIGN_OR_RETURN(last, fem_->Settle());
  }
  return AfterStep(FromSolve(last, t0));
}

Result<SceneStepTimings> DeformableScene::Release(bool keep) {
  const auto t0 = std::chrono::steady_clock::now();
  // The drag is finished first: a kept drag keeps its target, not how far
  // the bounded events had come (as Grab).
  RETURN_IF_ERROR(Settle(kSettleSolves).status());
  RETURN_IF_ERROR(fem_->Release(keep));
  Record({.kind = SceneOp::Kind::kRelease, .keep = keep});
  grab_point_mm_.reset();
  drag_offset_mm_ = glm::dvec3(0.0);
  SceneStepTimings timings;
  // With something held the tissue relaxes towards it: one bounded solve
  // now, Settle goes on.
  if (!fem_->settled()) {
    ASSIGN_OR_RETURN(const SolveStats solve, fem_->Settle());
    timings = FromSolve(solve, t0);
  }
  timings.fem_ms = MsSince(t0);
  return AfterStep(timings);
}

std::optional<glm::dvec3> DeformableScene::GrabbedTissueMm() const {
  if (!grab_point_mm_) return std::nullopt;
  return *grab_point_mm_ + drag_offset_mm_;
}

ClipRegion DeformableScene::ViewClip(const SceneView& view) const {
  ClipRegion clip = view.clip;
  if (view.view_cut) {
    const VolumeGeometry& g = volume_->geometry();
    const glm::dvec3 at_mm = GrabbedTissueMm().value_or(view.camera.Target());
    clip.planes.push_back(
        CutPlaneFacing(g.PhysicalToWorld(at_mm), g.direction * view.camera.Forward()));
  }
  return clip;
}

Result<Frame> DeformableScene::Render(const SceneView& view, SceneStepTimings* map_update) {
  ASSIGN_OR_RETURN(const RenderRequest request, PrepareRender(view, map_update));
  return RenderPrepared(request);
}

Result<Frame> DeformableScene::RenderPrepared(const RenderRequest& request) const {
  return renderer_->Render(request);
}

InteractiveQuality AutoInteractiveQuality(const gpu::GpuContext& context) {
  return context.is_discrete_gpu() ? InteractiveQuality::kSharp : InteractiveQuality::kFast;
}

RenderRequest ViewRenderRequest(const SceneView& view, InteractiveQuality auto_quality) {
  RenderRequest request;
  request.camera = view.camera;
  request.mode = view.mode;
  request.preset = view.preset;
  request.quality = view.quality;
  request.interactive = InteractiveCastFor(view.interactive_quality == InteractiveQuality::kAuto
                                               ? auto_quality
                                               : view.interactive_quality);
  request.width = view.width;
  request.height = view.height;
  request.settings.step_mm = view.step_mm;
  return request;
}

Result<RenderRequest> DeformableScene::PrepareRender(const SceneView& view,
                                                     SceneStepTimings* map_update) {
  ASSIGN_OR_RETURN(SceneStepTimings sync, SyncMap());
  if (map_update != nullptr) *map_update = sync;
  RenderRequest request = ViewRenderRequest(view, auto_interactive_quality());
  request.clip = ViewClip(view);
  if (view.quality == RenderQuality::kInteractive) {
    request.settings.jitter_seed = ++interactive_frames_;
  } else {
    MakeRefineRung(request, view.refine_step_multiple, volume_->geometry());
  }
  request.volume = gpu_volume_;
  // Undeformed (every displacement 0): no map, the identity, whose reads
  // would cost a third of the cast for the same picture.
  if (!map_identity_) {
    request.backward_map = &map_->image();
    // Frames between drag steps (orbit, zoom, preset of the same mode) reuse
    // the brick occupancy, and the ray caster reads the map's own buffer.
    request.backward_map_version = map_version_;
    request.backward_map_previous_version = map_previous_version_;
    request.backward_map_changed_lo = map_changed_.lo;
    request.backward_map_changed_hi = map_changed_.hi;
    request.backward_map_texels = map_->values_buffer();
  }
  if (view.overlay) {
    const std::vector<glm::dvec3> positions = fem_->Positions();
    const auto& handles = fem_->grabbed() ? fem_->grab().handles : std::vector<int32_t>{};
    request.overlay = MakeMeshOverlay(mesh_, positions, handles);
    if (grab_point_mm_) {
      request.overlay.drag = DragArrow{*grab_point_mm_, *grab_point_mm_ + drag_offset_mm_};
    }
  }
  return request;
}

Result<SliceFrame> DeformableScene::RenderSlice(const SliceView& view) {
  RETURN_IF_ERROR(SyncMap().status());
  SliceFrame frame;
  frame.window = view.window.value_or(DefaultSliceWindow(*volume_));
  RETURN_IF_ERROR(ValidateMipWindow(frame.window));
  ASSIGN_OR_RETURN(frame.grid, MakeSliceGrid(view.plane, volume_->geometry(), view.pixel_mm));
  if (!slice_sampler_) {
    ASSIGN_OR_RETURN(SliceSampler sampler, SliceSampler::Create(*context_));
    slice_sampler_.emplace(std::move(sampler));
  }
  ASSIGN_OR_RETURN(const std::vector<float> values,
                   slice_sampler_->Sample(*gpu_volume_, map_->image(), map_->dims(), frame.grid,
                                          &frame.gpu_ms));
  frame.rgba = SliceToRgba(values, frame.grid.width, frame.grid.height, frame.window);
  if (view.overlay) {
    const std::vector<glm::dvec3> positions = fem_->Positions();
    frame.cut_tets = DrawCutTets(frame.grid, positions, mesh_.tets, kDeformableRgb, frame.rgba);
    if (const auto grabbed = GrabbedTissueMm()) {
      DrawSliceMarker(frame.grid, *grabbed, mesh_.stats.h_mm, kHandleRgb, frame.rgba);
    }
  }
  return frame;
}

Result<BackwardMap> DeformableScene::ExactMap() const {
  // Export through an exact map (one point per voxel centre), not the coarse
  // interactive one: docs/WARP.md measures what the coarse map costs.
  BackwardMap::Options exact;
  exact.map_dims = volume_->dims();
  ASSIGN_OR_RETURN(BackwardMap map, BackwardMap::Create(*context_, volume_->geometry(), exact));
  RETURN_IF_ERROR(map.Update(fem_->rest_positions_mm(), fem_->Positions(), fem_->tets()).status());
  return map;
}

Result<Volume> DeformableScene::WarpedVolume() {
  ASSIGN_OR_RETURN(const BackwardMap map, ExactMap());
  ASSIGN_OR_RETURN(VolumeWarper warper, VolumeWarper::Create(*context_));
  return warper.Warp(*gpu_volume_, *volume_, map);
}

Result<std::vector<glm::vec3>> DeformableScene::DisplacementField() {
  ASSIGN_OR_RETURN(const BackwardMap map, ExactMap());
  ASSIGN_OR_RETURN(const BackwardMapValues values, map.Download());
  // The map holds X(p) - p in physical voxel space; world LPS rotates it by
  // the volume's direction (no origin: it is an offset).
  const glm::dmat3& direction = volume_->geometry().direction;
  std::vector<glm::vec3> out(values.values.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const glm::vec4& v = values.values[i];
    out[i] = v.w > 0.5f ? glm::vec3(direction * glm::dvec3(v.x, v.y, v.z)) : glm::vec3(0.0f);
  }
  return out;
}

}  // namespace vpm

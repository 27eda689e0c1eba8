#include "server/service/session.h"

#include <chrono>
#include <cmath>

#include "server/common/clock.h"
#include "server/raycast/frame_encoder.h"
#include "server/common/prefix_status.h"

namespace vpm::service {
namespace {

// The largest grab radius (mm), drag offset (mm) or pull force (N) a client
// may send: ten metres, or ten kilonewtons, is past anything a body allows;
// numbers far larger overflow the FEM model.
constexpr double kMaxEventMagnitude = 1e4;

Status CheckGrabRadius(double radius_mm) {
  if (std::isfinite(radius_mm) && radius_mm >= 0 && radius_mm <= kMaxEventMagnitude) {
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(StrCat("grab.radius_mm: must be a finite number of mm in [0, ",
                                           kMaxEventMagnitude, "] (0: one lattice step)"));
}

// A drag offset (mm) or pull force (N): finite, and at most kMaxEventMagnitude long.
Status CheckMotion(const glm::dvec3& v, const char* field) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
    return absl::InvalidArgumentError(StrCat(field, ": not finite"));
  }
  if (glm::length(v) > kMaxEventMagnitude) {
    return absl::InvalidArgumentError(
        StrCat(field, ": longer than ", kMaxEventMagnitude, " (mm or N)"));
  }
  return absl::OkStatus();
}

// The frame's picture and slices into `out`: PNG, or JPEG at the stream's
// quality (75 at most while interactive).
Status EncodeFrameImages(const Frame& frame, const std::vector<SliceFrame>& slices,
                         const StreamSettings& s, bool interactive, const VolumeGeometry& g,
                         v3::Frame& out) {
  const int jpeg_quality = interactive ? std::min(s.jpeg_quality, 75) : s.jpeg_quality;
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                   s.png ? EncodePng(frame.rgba, frame.width, frame.height)
                         : EncodeJpeg(frame.rgba, frame.width, frame.height, jpeg_quality));
  out.set_image(bytes.data(), bytes.size());
  for (size_t i = 0; i < slices.size(); ++i) {
    ASSIGN_OR_RETURN(*out.add_slices(),
                     EncodeSliceImage(slices[i], s.slices[i], g, s.png, jpeg_quality));
  }
  out.set_encoding(s.png ? v3::ENCODING_PNG : v3::ENCODING_JPEG);
  out.set_width(frame.width);
  out.set_height(frame.height);
  return absl::OkStatus();
}

// A refinement rung: a still cast at a multiple of its own step
// (FrameStream's ladder), sent as interactive.
bool IsRefineRung(const Session::FrameRequest& request) {
  return !request.interactive && request.refine_step_multiple > 1.0;
}

// The model cannot follow a drag or pull this large (its state became
// non-finite and was restored): the request's fault, not the server's.
Status MotionRefused(const Status& status, const char* field) {
  if (!absl::IsInternal(status)) return status;
  return absl::InvalidArgumentError(
      StrCat(field, ": the model cannot follow this (", status.message(), "); ask for less"));
}

}  // namespace

Session::Session(std::string id, std::string owner, VolumeHold volume,
                 std::shared_ptr<const MeshEntry> mesh, const Options& options)
    : id_(std::move(id)),
      access_(std::move(owner)),
      hold_(std::move(volume)),
      volume_(hold_.volume()),
      mesh_(std::move(mesh)),
      options_(options),
      camera_(Camera::ForVolume(volume_->volume.geometry())),
      last_touch_(std::chrono::steady_clock::now()) {}

Result<std::shared_ptr<Session>> Session::Create(std::string id, std::string owner,
                                                 const gpu::GpuContext& context, VolumeHold hold,
                                                 std::shared_ptr<const MeshEntry> mesh,
                                                 const Options& options) {
  const std::shared_ptr<VolumeEntry> volume = hold.volume();
  std::shared_ptr<Session> session(
      new Session(std::move(id), std::move(owner), std::move(hold), mesh, options));
  std::lock_guard gpu_lock(volume->gpu_mutex);
  // Events update FEM only; each frame brings the backward map up to date
  // once, however many steps came since (a slow stream or a busy server
  // would otherwise pay a map update per event it never shows).
  DeformableScene::Options scene_options;
  scene_options.defer_map_update = true;
  ASSIGN_OR_RETURN(session->renderer_, VolumeRenderer::Create(context, {}));
  ASSIGN_OR_RETURN(session->scene_,
                   DeformableScene::Create(context, volume->volume, volume->gpu,
                                           *session->renderer_, mesh->mesh, scene_options));
  return session;
}

Result<glm::dvec3> Session::GrabPoint(const v3::Grab& grab, const SceneView* stream_view) const {
  const Volume& volume = volume_->volume;
  if (!grab.pick()) {
    const glm::dvec3 p = PointFromApi(grab.point_mm(), volume.geometry());
    RETURN_IF_ERROR(CheckInsideVolume(volume.geometry(), p, "grab.point_mm"));
    return p;
  }
  // The frame the pixel belongs to, as it was shown, with today's camera.
  // The caller (ApplyLocked) holds scene_mutex_, so the scene's grab state
  // that places the view cut cannot change under the pick.
  SceneView shown;
  {
    std::lock_guard lock(state_mutex_);
    shown = stream_view != nullptr ? *stream_view : last_view_;
    shown.camera = camera_;
  }
  Result<glm::dvec3> picked = scene_->Pick(shown, grab.pixel_x(), grab.pixel_y());
  if (!picked.ok()) return PrefixStatus(picked.status(), "grab.pixel");
  return picked;
}

Result<AppliedEvent> Session::Apply(const v3::ClientEvent& event, const SceneView* view) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  Touch();
  std::unique_lock scene_lock(scene_mutex_);
  std::vector<SceneOp> before;
  if (case_store_ != nullptr) before = scene_->history();
  ASSIGN_OR_RETURN(AppliedEvent applied, ApplyLocked(event, view));
  if (Status stored = StoreInCase(event, before, scene_lock); !stored.ok()) {
    Changed(0, true, nullptr);
    return stored;
  }
  Changed(event.sequence(), applied.deformed, applied.deformed ? &applied.step : nullptr);
  return applied;
}

Result<AppliedEvent> Session::ApplyLocked(const v3::ClientEvent& event, const SceneView* view) {
  AppliedEvent applied;
  switch (event.event_case()) {
    case v3::ClientEvent::kCamera: {
      ASSIGN_OR_RETURN(Camera camera, ToCamera(event.camera(), volume_->volume.geometry()));
      std::lock_guard lock(state_mutex_);
      camera_ = camera;
      return applied;
    }
    case v3::ClientEvent::kGrab:
      return ApplyGrab(event.grab(), view);
    case v3::ClientEvent::kPin:
      return ApplyPin(event.pin(), view);
    case v3::ClientEvent::kReset: {
      ASSIGN_OR_RETURN(applied.step, scene_->Reset());
      applied.deformed = true;
      return applied;
    }
    case v3::ClientEvent::kDrag:
    case v3::ClientEvent::kPull: {
      if (!scene_->GrabPointMm()) {
        return absl::FailedPreconditionError(event.has_drag()
                                                 ? "drag: no grab in effect; send a grab first"
                                                 : "pull: no grab in effect; send a grab first");
      }
      const glm::dvec3 v = VectorFromApi(
          event.has_drag() ? event.drag().offset_mm() : event.pull().force_n(),
          volume_->volume.geometry());
      const char* field = event.has_drag() ? "drag.offset_mm" : "pull.force_n";
      RETURN_IF_ERROR(CheckMotion(v, field));
      Result<SceneStepTimings> step = event.has_drag() ? scene_->Drag(v) : scene_->Pull(v);
      if (!step.ok()) return MotionRefused(step.status(), field);
      applied.step = *step;
      applied.deformed = true;
      return applied;
    }
    case v3::ClientEvent::kRelease: {
      if (!scene_->GrabPointMm()) {
        return absl::FailedPreconditionError("release: no grab in effect");
      }
      ASSIGN_OR_RETURN(applied.step, scene_->Release(event.release().keep()));
      applied.deformed = true;
      return applied;
    }
    case v3::ClientEvent::kSettings:
    case v3::ClientEvent::EVENT_NOT_SET:
      return applied;
  }
  return applied;
}

Result<AppliedEvent> Session::ApplyGrab(const v3::Grab& grab, const SceneView* view) {
  ASSIGN_OR_RETURN(glm::dvec3 point, GrabPoint(grab, view));
  RETURN_IF_ERROR(CheckGrabRadius(grab.radius_mm()));
  const GrabRule rule = grab.rule() == v3::GRAB_RULE_BALL ? GrabRule::kBall : GrabRule::kOrgan;
  ASSIGN_OR_RETURN(GrabInfo info, scene_->Grab(GrabRequest{
                                      .point_mm = point, .rule = rule,
                                      .radius_mm = grab.radius_mm()}));
  AppliedEvent applied;
  applied.grab_point_mm = point;
  applied.grab = std::move(info);
  RefineAtGrab(point);
  return applied;
}

Result<AppliedEvent> Session::ApplyPin(const v3::Pin& pin, const SceneView* view) {
  // A pin is placed as a grab is: by point or by a pixel of the frame.
  v3::Grab where;
  *where.mutable_point_mm() = pin.point_mm();
  where.set_pick(pin.pick());
  where.set_pixel_x(pin.pixel_x());
  where.set_pixel_y(pin.pixel_y());
  ASSIGN_OR_RETURN(glm::dvec3 point, GrabPoint(where, view));
  RETURN_IF_ERROR(CheckGrabRadius(pin.radius_mm()));
  AppliedEvent applied;
  ASSIGN_OR_RETURN(applied.step, scene_->Pin(point, pin.radius_mm()));
  applied.deformed = true;
  return applied;
}

Status Session::SetCamera(const v3::Camera& camera) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  Touch();
  ASSIGN_OR_RETURN(Camera c, ToCamera(camera, volume_->volume.geometry()));
  {
    std::lock_guard lock(state_mutex_);
    camera_ = c;
  }
  Changed(0, false, nullptr);
  StoreCameraInCase(camera);
  return absl::OkStatus();
}

void Session::Changed(uint64_t sequence, bool deformed, const SceneStepTimings* step) {
  {
    std::lock_guard lock(state_mutex_);
    ++version_;
    last_change_ = std::chrono::steady_clock::now();
    if (sequence > last_sequence_) last_sequence_ = sequence;
    if (deformed && step != nullptr) last_step_ = *step;
  }
  Notify(false);
}

Result<v3::Frame> Session::Render(const FrameRequest& request) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  const auto t0 = std::chrono::steady_clock::now();
  const bool interactive = request.interactive;
  const bool rung = IsRefineRung(request);
  v3::Frame out;
  // The map stays as this frame's request saw it until the frame is cast;
  // the scene itself is free meanwhile, so the next event's FEM runs while
  // this frame renders (DeformableScene::PrepareRender).
  std::unique_lock frame_lock(frame_mutex_);
  ASSIGN_OR_RETURN(PreparedFrame prepared, PrepareFrame(request, out));
  RETURN_IF_ERROR(request.cancel.Check());
  prepared.render.cancel = request.cancel;
  ASSIGN_OR_RETURN(const Frame frame, scene_->RenderPrepared(prepared.render));
  frame_lock.unlock();
  // A still: the client has stopped changing things; its view, if new, goes
  // to the case now rather than with every settings event.
  if (!interactive && !rung) StoreViewInCase();
  const double render_ms = MsSince(t0) - prepared.map_update.warp_ms;
  const auto t1 = std::chrono::steady_clock::now();
  RETURN_IF_ERROR(EncodeFrameImages(frame, prepared.slices, *request.settings, interactive,
                                    volume_->volume.geometry(), out));
  out.set_interactive(interactive || rung);
  out.set_last_sequence(prepared.sequence);
  const SceneStepTimings& step = prepared.step;
  out.set_max_displacement_mm(step.max_displacement_mm);
  out.set_inverted_tets(step.inverted_tets);
  out.set_lag_mm(step.lag_mm);
  v3::StageTimings* timings = out.mutable_timings();
  timings->set_fem_ms(step.fem_ms);
  timings->set_warp_ms(prepared.map_update.warp_ms);
  timings->set_render_ms(render_ms);
  timings->set_encode_ms(MsSince(t1));
  timings->set_total_ms(MsSince(t0));
  return out;
}

Result<Session::PreparedFrame> Session::PrepareFrame(const FrameRequest& request,
                                                     v3::Frame& out) {
  const bool interactive = request.interactive;
  SceneView view = request.settings->view;
  view.quality = interactive ? RenderQuality::kInteractive : RenderQuality::kStill;
  if (IsRefineRung(request)) view.refine_step_multiple = request.refine_step_multiple;
  PreparedFrame prepared;
  // The state is read under the scene lock, so the frame shows exactly the
  // events it reports.
  std::lock_guard scene_lock(scene_mutex_);
  SwapInRefinedMeshLocked();
  {
    std::lock_guard lock(state_mutex_);
    view.camera = request.camera ? *request.camera : camera_;
    prepared.step = last_step_;
    prepared.sequence = last_sequence_;
    last_view_ = view;
    out.set_mesh_id(mesh_->id);
    if (const auto grabbed = scene_->GrabPointMm()) {
      *out.mutable_grab_point_mm() = PointToApi(*grabbed, volume_->volume.geometry());
    }
  }
  // A still comes once the pointer has stopped: the drag the per-event
  // bound left short of its offset is finished first (docs/FEM.md,
  // "Per-event work bound"), so the still shows where the pointer is.
  if (!interactive) RETURN_IF_ERROR(SettleLocked(&prepared.step));
  ASSIGN_OR_RETURN(prepared.render, scene_->PrepareRender(view, &prepared.map_update));
  // Slices are cheap (a few ms): cast here, under the scene lock, from the
  // map this frame uses.
  ASSIGN_OR_RETURN(prepared.slices, RenderSlicesLocked(request.settings->slices));
  if (request.want_vertices) {
    for (const glm::dvec3& p : scene_->Positions()) {
      *out.add_vertices_mm() = PointToApi(p, volume_->volume.geometry());
    }
  }
  return prepared;
}

std::vector<double> Session::RefineLadder(const StreamSettings& settings,
                                          double min_still_ms) const {
  SceneView view = settings.view;
  {
    std::lock_guard lock(state_mutex_);
    view.camera = camera_;
  }
  view.quality = RenderQuality::kInteractive;
  const RenderRequest interactive = ViewRenderRequest(view, scene_->auto_interactive_quality());
  // The still casts every pixel of the frame.
  const int64_t still_rays = int64_t(interactive.width) * interactive.height;
  if (!StillWorthRungs(renderer_->PredictStillMs(still_rays), min_still_ms)) return {};
  return vpm::RefineLadder(interactive, volume_->volume.geometry());
}

Status Session::SettleLocked(SceneStepTimings* step) {
  ASSIGN_OR_RETURN(const SceneStepTimings settled, scene_->Settle(kSettleSolves));
  if (settled.fem_ms <= 0.0) return absl::OkStatus();
  step->max_displacement_mm = settled.max_displacement_mm;
  step->inverted_tets = settled.inverted_tets;
  step->lag_mm = settled.lag_mm;
  {
    std::lock_guard lock(state_mutex_);
    last_step_.max_displacement_mm = step->max_displacement_mm;
    last_step_.inverted_tets = step->inverted_tets;
    last_step_.lag_mm = step->lag_mm;
  }
  RecordSettleInCase();
  return absl::OkStatus();
}

Result<std::vector<SliceFrame>> Session::RenderSlicesLocked(
    const std::vector<SliceRequest>& requests) {
  std::vector<SliceFrame> frames;
  for (const SliceRequest& request : requests) {
    const SliceView view =
        PlaceSlice(request, volume_->volume.geometry(), scene_->GrabbedTissueMm());
    ASSIGN_OR_RETURN(SliceFrame frame, scene_->RenderSlice(view));
    frames.push_back(std::move(frame));
  }
  return frames;
}

Result<v3::Frame> Session::RenderSlice(const SliceRequest& request, bool png, int jpeg_quality) {
  if (closed()) return absl::FailedPreconditionError(StrCat("session '", id_, "' is closed"));
  const auto t0 = std::chrono::steady_clock::now();
  v3::Frame out;
  SliceFrame frame;
  {
    // The slice may update the map (SyncMap), which a frame being cast
    // outside the scene lock reads: frame lock first (session.h).
    std::lock_guard frame_lock(frame_mutex_);
    std::lock_guard scene_lock(scene_mutex_);
    {
      std::lock_guard lock(state_mutex_);
      out.set_last_sequence(last_sequence_);
      out.set_max_displacement_mm(last_step_.max_displacement_mm);
      if (const auto grabbed = scene_->GrabPointMm()) {
        *out.mutable_grab_point_mm() = PointToApi(*grabbed, volume_->volume.geometry());
      }
    }
    ASSIGN_OR_RETURN(std::vector<SliceFrame> frames, RenderSlicesLocked({request}));
    frame = std::move(frames.front());
  }
  const double render_ms = MsSince(t0);
  const auto t1 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(v3::SliceImage image,
                   EncodeSliceImage(frame, request, volume_->volume.geometry(), png, jpeg_quality));
  out.set_image(std::move(*image.mutable_image()));
  out.set_encoding(image.encoding());
  out.set_width(image.width());
  out.set_height(image.height());
  *out.mutable_slice() = std::move(*image.mutable_geometry());
  out.mutable_timings()->set_render_ms(render_ms);
  out.mutable_timings()->set_encode_ms(MsSince(t1));
  out.mutable_timings()->set_total_ms(MsSince(t0));
  return out;
}

bool Session::RecentlyChanged() const {
  std::lock_guard lock(state_mutex_);
  if (last_change_ == std::chrono::steady_clock::time_point{}) return false;
  return MsSince(last_change_) < options_.still_delay_ms;
}

uint64_t Session::version() const {
  std::lock_guard lock(state_mutex_);
  return version_;
}

uint64_t Session::last_sequence() const {
  std::lock_guard lock(state_mutex_);
  return last_sequence_;
}

double Session::max_displacement_mm() const {
  std::lock_guard lock(state_mutex_);
  return last_step_.max_displacement_mm;
}

int64_t Session::AddObserver(Observer observer) {
  std::lock_guard lock(observers_mutex_);
  const int64_t token = next_observer_++;
  observers_.emplace(token, std::move(observer));
  return token;
}

void Session::RemoveObserver(int64_t token) {
  std::lock_guard lock(observers_mutex_);
  observers_.erase(token);
}

int32_t Session::viewers() const {
  std::lock_guard lock(observers_mutex_);
  return static_cast<int32_t>(observers_.size());
}

void Session::Notify(bool closed) {
  std::vector<Observer> observers;
  {
    std::lock_guard lock(observers_mutex_);
    for (const auto& [token, observer] : observers_) observers.push_back(observer);
  }
  for (const Observer& observer : observers) observer(closed);
}

void Session::Close() {
  {
    std::lock_guard lock(state_mutex_);
    if (closed_) return;
    closed_ = true;
  }
  refine_cancel_.Cancel();
  StoreViewInCase();
  Notify(true);
}

bool Session::closed() const {
  std::lock_guard lock(state_mutex_);
  return closed_;
}

void Session::Touch() {
  std::lock_guard lock(state_mutex_);
  last_touch_ = std::chrono::steady_clock::now();
}

double Session::idle_s() const {
  std::lock_guard lock(state_mutex_);
  return MsSince(last_touch_) / 1000.0;
}

}  // namespace vpm::service

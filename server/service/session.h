// One deformation case that clients attach to: a shared volume, a mesh, the
// DeformableScene (FEM + backward map) and the camera every viewer shares.
// Render settings belong to each stream; the owner's last ones are also kept
// as the session's view (KeepView), which its case stores. Thread-safe: scene work is
// serialised by a mutex, frames by another, so that the FEM of an event
// runs while a frame renders; state changes bump a version and notify the
// attached streams, which render on the worker pool.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "server/cases/case_store.h"
#include "server/common/cancel_token.h"
#include "server/raycast/volume_renderer.h"
#include "server/scene/deformable_scene.h"
#include "server/service/mesh_store.h"
#include "server/service/proto_convert.h"
#include "server/service/session_access.h"
#include "server/service/volume_store.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

// What applying one event did.
struct AppliedEvent {
  SceneStepTimings step;  // FEM and warp times (zero for camera events)
  bool deformed = false;
  std::optional<glm::dvec3> grab_point_mm;  // a grab's point (picked or given)
  std::optional<GrabInfo> grab;              // a grab's handles and message
};

class Session : public std::enable_shared_from_this<Session> {
 public:
  // Refinement without asking (docs/SERVICE.md): builds the mesh
  // `mesh_id` refined at `point_mm` (physical) beside the running one, off
  // the caller's thread, and hands the result to session->OfferRefinedMesh
  // (if the session still lives). `cancel` ends it when the session closes.
  using RefineFn = std::function<void(std::weak_ptr<Session> session, std::string mesh_id,
                                      glm::dvec3 point_mm, CancelToken cancel)>;
  struct Options {
    double still_delay_ms = 150;  // a frame is interactive this long after a drag
    RefineFn refine;              // empty: a grab never refines by itself
  };
  // The scene is built here (FEM set-up), with a renderer of the session's
  // own: call from a worker, not a callback. `owner`: the user who opens it
  // (session_access.h); `volume`: the owner's hold on the session's volume
  // (VolumeStore::HoldForSession), kept until the session is destroyed.
  static Result<std::shared_ptr<Session>> Create(std::string id, std::string owner,
                                                 const gpu::GpuContext& context, VolumeHold volume,
                                                 std::shared_ptr<const MeshEntry> mesh,
                                                 const Options& options);

  const std::string& id() const { return id_; }
  // Its owner and the users it is shared with.
  SessionAccess& access() { return access_; }
  const SessionAccess& access() const { return access_; }
  const VolumeEntry& volume() const { return *volume_; }
  // The mesh in use: it changes when a refinement is swapped in.
  std::shared_ptr<const MeshEntry> mesh() const;
  // A refinement started by a grab has finished: the next frame swaps it in
  // (between events, under the frame and scene locks), replaying the
  // manipulation onto it (DeformableScene::Rebuilt). Errors are logged and
  // the running mesh stays.
  void OfferRefinedMesh(Result<std::shared_ptr<const MeshEntry>> refined);
  // Refinements swapped in so far, and the last swap's time (ms: the new
  // scene's set-up and the replay).
  int64_t refinements() const;
  double last_swap_ms() const;

  // Camera, grab (point or pick), drag, pull, release. Settings events are
  // the stream's business and ignored here. Errors: InvalidArgument naming
  // the field, OutOfRange for a point outside the volume,
  // FailedPrecondition for a drag, pull or release without a grab.
  // `view`: the settings of the stream that sent the event, for a grab by
  // pixel (frame size, preset and mode of the frame the user clicked);
  // null (Manipulate) uses those of the last frame rendered.
  // With a case attached, a manipulation is stored in the case before
  // Apply returns; when the store refuses it (a full disk, a locked
  // database) the scene goes back to what the case holds and the store's
  // error is returned: what a client saw acknowledged is what is stored.
  Result<AppliedEvent> Apply(const v3::ClientEvent& event, const SceneView* view = nullptr);
  Status SetCamera(const v3::Camera& camera);

  // The case this session is open on (docs/CASES.md, session_case.cc):
  // call once, before the session is shared (OpenSession, OpenCase).
  // Replays `ops` (the case's events since its last reset:
  // SinceLastReset) exactly onto the scene and sets `camera` (a serialized
  // vpm.v3.Camera; empty: keep the default) and the kept view
  // (`render_settings`, a serialized vpm.v3.RenderSettings; empty: none).
  // DataLoss when the camera or the view do not parse.
  Status AttachCase(cases::CaseStore* store, std::string case_id, const std::vector<SceneOp>& ops,
                    const std::string& camera, const std::string& render_settings = "");
  const std::string& case_id() const { return case_id_; }
  // Undo (redo = false) or redo one action of the case; the scene is
  // replayed from the case's events in effect. FailedPrecondition without
  // a case.
  struct UndoOutcome {
    bool changed = false;
    double max_displacement_mm = 0.0;
    int64_t events = 0;
    int64_t undone = 0;
  };
  Result<UndoOutcome> Undo(bool redo);

  // The view (session_view.cc): the render settings an Interact stream of
  // the owner set last, less the per-client fields (CaseView). Kept at
  // once, on the event path without a write; the case stores it, when it
  // changed, with the next still frame of the session and when the session
  // closes (StoreViewInCase), so that a crop or clip drag costs one write
  // at its end. A view over kMaxCaseViewBytes is not kept (logged).
  void KeepView(const v3::RenderSettings& settings);
  // The kept view; nullopt when none was (no client set settings and the
  // case had none).
  std::optional<v3::RenderSettings> kept_view() const;
  // One frame of the current state, encoded. `camera` overrides the
  // session's; `interactive` picks the cheap quality (streams use it while
  // drags keep coming, frame_stream.h).
  struct FrameRequest {
    const StreamSettings* settings = nullptr;
    std::optional<Camera> camera;
    bool interactive = false;
    bool want_vertices = false;
    // Polled between the bands of a still and before the cast: a frame
    // nobody waits for (Render cancelled or past its deadline) stops.
    CancelToken cancel;
    // Not interactive: > 1 casts the refinement rung at this multiple of
    // the still's step (refine_ladder.h); the frame says interactive, and
    // the rung, like the still, shows the settled state.
    double refine_step_multiple = 0.0;
  };
  Result<v3::Frame> Render(const FrameRequest& request);
  // The refinement rungs (step multiples of the still's, coarsest first:
  // RefineLadder) for frames of `settings` at the session's camera; none
  // where the session's renderer predicts the still under min_still_ms
  // (StillWorthRungs).
  std::vector<double> RefineLadder(const StreamSettings& settings, double min_still_ms) const;
  // One slice of the current state (RenderSlice): the Frame's image is the
  // slice, Frame.slice where it lies.
  Result<v3::Frame> RenderSlice(const SliceRequest& request, bool png, int jpeg_quality);

  // What an export writes (session_export.cc): the settled state's
  // deformed volume on the source grid, a still 3D frame at the session's
  // camera and last render settings, and what was done.
  struct Exported {
    Volume deformed;
    Frame frame;                       // RGBA, rows top to bottom
    double max_displacement_mm = 0.0;  // of the exported state
    int64_t manipulations = 0;         // grabs and pins since the last reset
    std::optional<glm::dvec3> grab_world_mm;  // the grab in effect, world LPS mm
  };
  Result<Exported> Export(const CancelToken& cancel);

  // True while the last change (camera, grab, drag, pull, release,
  // settings; from any client) is younger than still_delay_ms: frames are
  // interactive meanwhile.
  bool RecentlyChanged() const;
  uint64_t version() const;
  uint64_t last_sequence() const;
  double max_displacement_mm() const;

  // Streams watching this session: notified (outside any session lock)
  // after every change, and with closed = true once when the session closes.
  using Observer = std::function<void(bool closed)>;
  int64_t AddObserver(Observer observer);
  void RemoveObserver(int64_t token);
  int32_t viewers() const;
  void Close();  // notifies observers; later calls fail with FailedPrecondition
  bool closed() const;

  void Touch();
  double idle_s() const;

 private:
  Session(std::string id, std::string owner, VolumeHold volume,
          std::shared_ptr<const MeshEntry> mesh, const Options& options);
  Result<AppliedEvent> ApplyLocked(const v3::ClientEvent& event, const SceneView* view);
  // The grab and pin events of ApplyLocked (scene lock held).
  Result<AppliedEvent> ApplyGrab(const v3::Grab& grab, const SceneView* view);
  Result<AppliedEvent> ApplyPin(const v3::Pin& pin, const SceneView* view);
  Result<glm::dvec3> GrabPoint(const v3::Grab& grab, const SceneView* view) const;
  // After a grab at point_mm: asks options_.refine for a mesh refined there
  // unless the mesh in use (or one on its way) already is, within h / 2.
  void RefineAtGrab(const glm::dvec3& point_mm);
  // The offered refinement, if any, replaces the scene (frame and scene
  // locks held).
  void SwapInRefinedMeshLocked();
  // A swap recorded in the case: its mesh parameters become the refined
  // mesh's, and a kRemesh event marks where (scene lock held). A refusal is
  // logged: the swap is not the user's event.
  void RecordRemeshInCase(const MeshEntry& refined);
  void Changed(uint64_t sequence, bool deformed, const SceneStepTimings* step);
  // After ApplyLocked changed the scene: stores its op in the case (no case:
  // nothing to do; a camera event: the camera). The caller holds
  // `scene_lock`; on a refusal the scene is replayed from the case (or
  // `before`, the history before the event, when the case cannot be read),
  // the lock released and taken again under the frame lock.
  Status StoreInCase(const v3::ClientEvent& event, const std::vector<SceneOp>& before,
                     std::unique_lock<std::mutex>& scene_lock);
  // The scene's largest displacement, inverted tets and lag as the last
  // step's (state_mutex_ held): after its scene was replaced.
  void TakeSceneStateLocked();
  // The camera in the case (no case: nothing); a refusal is logged.
  void StoreCameraInCase(const v3::Camera& camera);
  // The kept view in the case when it differs from what the case holds (no
  // case: nothing); a refusal is logged and retried with the next still.
  // Takes no other session lock.
  void StoreViewInCase();
  // The export's frame settings: the kept view, at the size of the last
  // frame rendered (none: 512 x 512); `last` is that frame's view.
  Result<SceneView> ExportView(const SceneView& last) const;
  // Replaces the scene by the mesh's with `ops` replayed (frame and scene
  // locks held), and records its displacement as the last step's.
  Status ReplaySceneLocked(const std::vector<SceneOp>& ops, DeformableScene::ReplayMode mode);
  // The case's events in effect since the last reset (the exact replay).
  Result<std::vector<SceneOp>> CaseHistory() const;
  // A still's Settle did work: the case records it, so that a replay takes
  // the same path (scene lock held). A refusal is logged: the still is not
  // the user's event.
  void RecordSettleInCase();
  // Finishes the drag the per-event bound left short (a still's settle);
  // when that moved anything, `step` and the last step take its
  // displacement and the case records the settle (scene lock held).
  Status SettleLocked(SceneStepTimings* step);
  // What a frame casts, read under the scene lock: the render request, the
  // slices, the last step's and this frame's map update's timings, the last
  // event's sequence.
  struct PreparedFrame {
    RenderRequest render;
    std::vector<SliceFrame> slices;
    SceneStepTimings step;
    SceneStepTimings map_update;
    uint64_t sequence = 0;
  };
  // Render's part under the scene lock (the caller holds frame_mutex_): the
  // view of `request`, the settle of a still, the map, the slices; the mesh
  // id, the grab point and the vertices go into `out`.
  Result<PreparedFrame> PrepareFrame(const FrameRequest& request, v3::Frame& out);
  // The slices `requests` place now; the caller holds scene_mutex_.
  Result<std::vector<SliceFrame>> RenderSlicesLocked(const std::vector<SliceRequest>& requests);
  void Notify(bool closed);

  const std::string id_;
  SessionAccess access_;
  VolumeHold hold_;
  std::shared_ptr<VolumeEntry> volume_;    // hold_'s
  std::shared_ptr<const MeshEntry> mesh_;  // under state_mutex_
  Options options_;

  // Lock order: frame_mutex_, scene_mutex_, state_mutex_. Whatever reads or
  // writes the backward map (frames: PrepareRender to RenderPrepared) holds
  // frame_mutex_; the scene's FEM and CPU state are under scene_mutex_
  // alone, so an event's FEM runs while a frame renders.
  std::mutex frame_mutex_;
  std::mutex scene_mutex_;  // the scene is single-threaded
  // The session's own renderer (its lookup table, brick occupancy and frame
  // buffers): frames of different sessions are recorded and cast side by
  // side, and a still frame, cast in bands (VolumeRenderer::Options::
  // still_band_rays), lets another session's frame run between its bands.
  // Before scene_, which renders with it.
  std::unique_ptr<VolumeRenderer> renderer_;
  std::unique_ptr<DeformableScene> scene_;

  mutable std::mutex state_mutex_;
  Camera camera_;
  uint64_t version_ = 0;
  uint64_t last_sequence_ = 0;
  SceneStepTimings last_step_;
  SceneView last_view_;  // settings of the last frame rendered (picks without a stream)
  std::optional<glm::dvec3> refining_at_;          // a refinement on its way (physical mm)
  std::shared_ptr<const MeshEntry> refined_mesh_;  // offered, not yet swapped in
  CancelToken::Source refine_cancel_;              // cancelled on Close
  int64_t refinements_ = 0;                        // swapped in so far
  double last_swap_ms_ = 0.0;                      // the last swap's rebuild and replay
  std::chrono::steady_clock::time_point last_change_{};
  std::chrono::steady_clock::time_point last_touch_;
  bool closed_ = false;
  // Set once by AttachCase, before the session is shared.
  cases::CaseStore* case_store_ = nullptr;
  std::string case_id_;

  // The kept view. view_mutex_ guards the three below and is taken alone;
  // view_store_mutex_ orders the writes (taken before view_mutex_).
  mutable std::mutex view_mutex_;
  std::optional<v3::RenderSettings> kept_view_;
  std::string kept_view_bytes_;    // kept_view_ serialized ("" when none)
  std::string stored_view_bytes_;  // what the case holds
  std::mutex view_store_mutex_;

  mutable std::mutex observers_mutex_;
  std::map<int64_t, Observer> observers_;
  int64_t next_observer_ = 1;
};

}  // namespace vpm::service

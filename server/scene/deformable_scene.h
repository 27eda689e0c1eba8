// One deformable case: a volume on the GPU, its proxy mesh under FEM, the
// backward map of the current deformation, and frames of it. The offline
// `vpm render`, the demo, the drag-loop benchmark and the server's sessions
// all drive this.
//
// Per drag step: FEM solve (CPU), backward-map update of the tets that moved
// (GPU), then any number of frames sampled through the map (GPU): the volume
// itself is never warped per frame (docs/LAVAPIPE.md: ~130 ms per 256^3 warp).
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "server/common/status.h"
#include "server/fem/fem_model.h"
#include "server/gpu/gpu_context.h"
#include "server/mesh/proxy_mesh.h"
#include "server/warp/backward_map.h"
#include "server/raycast/camera.h"
#include "server/raycast/clip_region.h"
#include "server/raycast/slice_sampler.h"
#include "server/scene/scene_history.h"
#include "server/scene/scene_op.h"
#include "server/scene/slice_view.h"
#include "server/raycast/refine_ladder.h"
#include "server/raycast/render_presets.h"
#include "server/raycast/volume_renderer.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/organ_region.h"
#include "server/volume/volume.h"

namespace vpm {

struct SceneStepTimings {
  double fem_ms = 0.0;   // wall: FEM solve (or release)
  double warp_ms = 0.0;  // wall: backward-map upload, update and wait
  double map_gpu_ms = 0.0;   // GPU: the map's passes (timestamps), part of warp_ms
  double map_copy_ms = 0.0;  // GPU: copying the map's changed box into its image
  std::vector<gpu::DispatchTiming> map_passes;  // GPU: clear (updates), claim, write
  int64_t moved_tets = 0;
  int64_t processed_tets = 0;  // moved plus those whose boxes meet them
  double max_displacement_mm = 0.0;
  int64_t inverted_tets = 0;  // after the FEM step (Drag, Pull, Release), not set by SyncMap
  double lag_mm = 0.0;  // spring handles: largest handle distance from its target, mm
  bool converged = true;
  SolveStats solve;  // the FEM solve's own counts and times (Drag, Pull)
};

struct SceneView {
  Camera camera;
  RenderMode mode = RenderMode::kDvr;
  RenderPreset preset;
  RenderQuality quality = RenderQuality::kStill;
  // How kInteractive frames trade speed for sharpness (InteractiveCastFor).
  InteractiveQuality interactive_quality = kDefaultInteractiveQuality;
  int width = 512;
  int height = 512;
  bool overlay = false;  // mesh vertices (deformable yellow, hard blue), handles, drag
  ClipRegion clip;       // crop box and clip planes, world (LPS) mm
  // Also cut away what lies in front of the plane that faces the camera
  // through the grabbed tissue (the grab point moved by the drag) or, with
  // nothing grabbed, through the orbit centre: the view shows the tissue
  // being moved, not the skin in front of it (DeformableScene::ViewClip).
  bool view_cut = false;
  // The sample step along the rays (mm); 0: the quality's default
  // (RaycastSettings::step_mm).
  double step_mm = 0.0;
  // kStill: > 1 casts the refinement rung at this multiple of the still's
  // step instead (MakeRefineRung, refine_ladder.h).
  double refine_step_multiple = 0.0;
};

// InteractiveQuality::kAuto on `context`'s device: kSharp on a discrete GPU
// (a 512^2 sharp frame casts in about 1.4 ms on an NVIDIA H200, and the drag
// loop keeps its rate, docs/RENDERING.md, "Interactive quality"), kFast on
// others (lavapipe: sharp 9.6 against fast 35 fps on the kidney CT).
InteractiveQuality AutoInteractiveQuality(const gpu::GpuContext& context);

// The render request's fields that follow from the view alone: camera,
// mode, preset, quality and its interactive cast (kAuto as auto_quality
// says), size and step (no clip, volume, map, jitter seed or refinement
// rung: PrepareRender adds those).
RenderRequest ViewRenderRequest(const SceneView& view, InteractiveQuality auto_quality);

// The interactive backward map: Update keeps the vertices that moved less
// than 0.05 mm (1/20 of a voxel of a 1 mm CT) since the map was last built
// where they were, so a drag step redoes the tets around the grab, not the
// whole mesh that FEM moves a little everywhere (docs/WARP.md).
inline BackwardMap::Options InteractiveMapOptions() {
  BackwardMap::Options options;
  options.move_tolerance_mm = 0.05;
  return options;
}

// Settle's bound for a still frame: the load steps towards one target are
// shared across solves (SolverOptions::max_load_steps, 32: at most 8 solves
// of 4 partial load steps before the rest is forced), plus a few solves to
// converge.
inline constexpr int kSettleSolves = 16;

// The organ grab's margin (GrabOrgan), in lattice steps h. On the kidney
// drag of tests/scene/kidney_drag_test.cc (mean along the drag, its
// coefficient of variation, bone's 95th percentile): 0: 86%, 0.18, 0.73 mm;
// 0.25 h: 89%, 0.14, 1.33 mm; 0.5 h: 91%, 0.12, 1.44 mm. The organ passes
// either way; bone stays best with none.
inline constexpr double kOrganMarginH = 0.0;

class DeformableScene {
 public:
  struct Options {
    BackwardMap::Options map = InteractiveMapOptions();
    // Bounded per event: a Drag may stop short of its offset and the next
    // one (or Settle) goes on (docs/FEM.md, "Per-event work bound").
    FemOptions fem = InteractiveFemOptions();
    // false: Drag, Pull and Release update the backward map at once (their
    // timings include it). true: they solve FEM only and mark the map stale;
    // the next Render (or SyncMap) updates it once for every step since, so
    // a burst of events costs one map update per frame (the server's
    // sessions: docs/SERVICE.md).
    bool defer_map_update = false;
  };

  // `volume`, `gpu_volume` and `renderer` must outlive the scene (the scene
  // may add the volume's 3D image to `gpu_volume` for export); the mesh
  // is copied.
  static Result<std::unique_ptr<DeformableScene>> Create(const gpu::GpuContext& context,
                                                         const Volume& volume,
                                                         GpuVolume& gpu_volume,
                                                         VolumeRenderer& renderer,
                                                         const ProxyMesh& mesh,
                                                         const Options& options);

  // Handles for the next Drag/Pull by request.rule; replaces an earlier grab
  // (a kept drag stays held). InvalidArgument for a non-finite point or a
  // bad radius; OutOfRange for a point outside the volume.
  Result<GrabInfo> Grab(const GrabRequest& request);
  // The paper's ball (GrabRule::kBall, radius_mm > 0).
  Result<GrabInfo> Grab(const glm::dvec3& point_mm, double radius_mm);
  // Holds the tissue within radius_mm (0: h / 2) of point_mm still while
  // another point is dragged (spring attachment only); the nearest
  // deformable vertex when none lies within.
  Result<SceneStepTimings> Pin(const glm::dvec3& point_mm, double radius_mm);
  // Back to rest: drops the grab, kept drags and pins.
  Result<SceneStepTimings> Reset();
  // Prescribed handle displacement from the grab (mm), or a total force (N).
  Result<SceneStepTimings> Drag(const glm::dvec3& offset_mm);
  Result<SceneStepTimings> Pull(const glm::dvec3& force_n);
  // Once the pointer stops: repeats the last Drag or Pull (FemModel::Settle)
  // until it has reached its target and converged, at most max_solves times
  // (each within the per-event bound). fem_ms: the wall of all of them;
  // solve: the last one's stats; nothing to do: all zero.
  Result<SceneStepTimings> Settle(int max_solves);
  bool settled() const { return fem_->settled(); }
  // Drops the grab. keep = false: back to rest where nothing is held (the
  // map becomes the identity again; deferred mode: at the next Render), else
  // the tissue relaxes to what kept drags and pins hold. keep = true: the
  // drag stays (spring attachment only).
  Result<SceneStepTimings> Release(bool keep = false);

  // Where the grabbed tissue is now: the grab point moved by the drag
  // (physical mm); empty with nothing grabbed. The view cut and the slice
  // marker pass through it.
  std::optional<glm::dvec3> GrabbedTissueMm() const;
  // The point of the grab in effect, at rest (physical mm); empty with
  // nothing grabbed.
  std::optional<glm::dvec3> GrabPointMm() const { return grab_point_mm_; }

  // The point pixel (pixel_x, pixel_y) of a frame of `view` shows, at rest
  // (server/raycast/pick_ray.h): DVR the first point where the composited
  // opacity reaches 0.5, MIP the brightest sample, both within the frame's
  // clip and view cut; a ray that shows nothing takes the plane through the
  // orbit centre that faces the camera. Physical mm. OutOfRange for a pixel
  // outside the frame or a plane point outside the volume.
  Result<glm::dvec3> Pick(const SceneView& view, int pixel_x, int pixel_y) const;

  // The clip region a frame of `view` uses: view.clip plus the view cut.
  ClipRegion ViewClip(const SceneView& view) const;

  // map_update (optional): the timings of the map update this frame needed
  // (deferred mode), zeros when the map was current. = PrepareRender, then
  // RenderPrepared.
  Result<Frame> Render(const SceneView& view, SceneStepTimings* map_update = nullptr);
  // A frame in two halves, so that the FEM of the next event can run while
  // this frame renders (the server's sessions, drag_loop_bench's overlap
  // row). PrepareRender brings the map up to date and copies everything the
  // frame needs from the scene into the request (camera, clip, overlay, the
  // map's image and version); RenderPrepared runs the GPU work and reads
  // nothing of the scene but the map and the volume. Between the two, in
  // deferred mode, Grab, Drag, Pull and Release may run on another thread
  // (they change FEM state only and mark the map stale); SyncMap, Render,
  // PrepareRender, RenderSlice and WarpedVolume must wait for
  // RenderPrepared to return, as they write or read the map.
  Result<RenderRequest> PrepareRender(const SceneView& view,
                                      SceneStepTimings* map_update = nullptr);
  Result<Frame> RenderPrepared(const RenderRequest& request) const;
  // What InteractiveQuality::kAuto means on this scene's device.
  InteractiveQuality auto_interactive_quality() const { return AutoInteractiveQuality(*context_); }
  // A slice of the deformed volume through the same backward map as the 3D
  // frames (deferred mode: brought up to date first).
  Result<SliceFrame> RenderSlice(const SliceView& view);
  // Brings the map up to date with FEM (deferred mode); zeros if it was.
  Result<SceneStepTimings> SyncMap();
  // The deformed volume at full resolution on the source grid (for export),
  // through an exact backward map (one point per voxel).
  Result<Volume> WarpedVolume();
  // The same exact map as a displacement field: per voxel of the source grid
  // (x fastest), the offset in world LPS mm from that point of the deformed
  // frame to the source point seen there (0 where no tet covers it); what
  // Slicer and ITK apply as a grid transform (write_displacement_field.h).
  Result<std::vector<glm::vec3>> DisplacementField();

  // What holds the tissue where it is now: the grabs, their last drag or
  // pull, kept releases and pins since rest, in order (a release that did
  // not keep drops its grab; Reset clears it). Drags and pulls are
  // absolute, so each grab keeps only its last.
  const std::vector<SceneOp>& history() const { return history_.ops(); }
  // The op the last successful Grab, Drag, Pull, Release, Pin or Reset
  // applied (what a case records); empty before any.
  const std::optional<SceneOp>& last_op() const { return last_op_; }
  // A new scene of the same volume, renderer and options on `mesh` (a
  // refinement of this one), with this scene's history replayed and
  // settled: the same manipulation on the finer mesh. The map is brought
  // up to date at its first frame (deferred mode) or at once.
  Result<std::unique_ptr<DeformableScene>> Rebuilt(const ProxyMesh& mesh) const;
  // How Replay applies ops. kFolded: a folded history (scene_history.h),
  // each drag settled (the same constraints; the state within the solver's
  // tolerance). kExact: a log of every op as applied, settles included, so
  // that the replay takes the same bounded steps (the same state, to the
  // last bit on the same build): a reopened case, or one after an undo.
  enum class ReplayMode { kFolded, kExact };
  // A new scene of the same volume, renderer and options on `mesh` with
  // `ops` replayed.
  Result<std::unique_ptr<DeformableScene>> Replayed(const ProxyMesh& mesh,
                                                    const std::vector<SceneOp>& ops,
                                                    ReplayMode mode) const;
  Status Replay(const std::vector<SceneOp>& ops, ReplayMode mode);

  const ProxyMesh& mesh() const { return mesh_; }
  const FemModel& fem() const { return *fem_; }
  std::vector<glm::dvec3> Positions() const { return fem_->Positions(); }
  const BackwardMap& backward_map() const { return *map_; }  // stale until SyncMap (deferred)
  // True while every FEM displacement is exactly 0 (before any drag, after a
  // release), as of the last map update: frames are then cast without the
  // map, which is the identity there (the same picture, a third less work).
  bool map_is_identity() const { return map_identity_; }

 private:
  DeformableScene() = default;
  Result<SceneStepTimings> UpdateMap(SceneStepTimings timings);
  // After FEM changed the deformation: update the map now, or mark it stale.
  Result<SceneStepTimings> AfterStep(SceneStepTimings timings);
  // A backward map with one point per voxel of the source grid, of the
  // current deformation.
  Result<BackwardMap> ExactMap() const;
  // Records an applied op in the history and as last_op_.
  void Record(const SceneOp& op);
  const gpu::GpuContext* context_ = nullptr;
  Options options_;
  SceneHistory history_;
  std::optional<SceneOp> last_op_;
  const Volume* volume_ = nullptr;
  GpuVolume* gpu_volume_ = nullptr;
  VolumeRenderer* renderer_ = nullptr;
  ProxyMesh mesh_;
  std::optional<FemModel> fem_;
  std::optional<BackwardMap> map_;
  std::optional<SliceSampler> slice_sampler_;  // made at the first slice
  std::optional<glm::dvec3> grab_point_mm_;
  glm::dvec3 drag_offset_mm_{0.0};
  // Changes with every map update (0 while one is in progress): frames with
  // the same version see the same map (RenderRequest::backward_map_version).
  uint64_t map_version_ = 0;
  // The version before the last update (0: none or unknown) and the grid
  // points that update changed: the renderer redoes only the brick
  // occupancy there (RenderRequest::backward_map_previous_version).
  uint64_t map_previous_version_ = 0;
  GridBox map_changed_;
  bool defer_map_update_ = false;
  bool map_stale_ = false;  // deferred mode: FEM moved since the last map update
  bool map_identity_ = true;  // every displacement 0 at the last map update
  // Interactive frames prepared so far: their jitter seed, so that the
  // jitter's noise changes from frame to frame while stills keep seed 0
  // (RaycastSettings::jitter_seed).
  uint32_t interactive_frames_ = 0;
};

}  // namespace vpm

#include "client/cli/offline_scene.h"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "client/common/progress_bar.h"
#include "server/common/clock.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/lattice_costs_gpu.h"
#include "server/mesh/mesh_frame.h"
#include "server/mesh/mesh_json.h"
#include "server/io/read_render_transfer_function.h"
#include "server/io/read_volume.h"
#include "server/raycast/render_preset_from_tf.h"

namespace vpm::cli {
namespace {

// How near the fixed skeleton lies to the grabbed tissue (what the
// inversion barrier may stop a drag against): the nearest skeleton vertex
// to any handle, and the nearest one ahead of the drag (on the side the
// drag moves towards), mm.
void PrintSkeletonNearHandles(const ProxyMesh& mesh, const std::vector<int32_t>& handles,
                              const glm::dvec3& drag_physical) {
  const double length = glm::length(drag_physical);
  double nearest = INFINITY, ahead = INFINITY;
  for (const MeshVertex& s : mesh.vertices) {
    if (!s.skeleton) continue;
    for (int32_t h : handles) {
      const glm::dvec3 d = s.position_mm - mesh.vertices[h].position_mm;
      const double distance = glm::length(d);
      nearest = std::min(nearest, distance);
      if (length > 0 && glm::dot(d, drag_physical) > 0) ahead = std::min(ahead, distance);
    }
  }
  if (!std::isfinite(nearest)) return;
  char ahead_text[32] = "none";
  if (std::isfinite(ahead)) std::snprintf(ahead_text, sizeof ahead_text, "%.1f mm", ahead);
  std::printf("skeleton nearest the handles %.1f mm; nearest ahead of the drag %s\n", nearest,
              ahead_text);
}

// `grab_mm` (physical voxel space, the point GrabPoint resolved from --grab
// or --grab-landmark): where the mesh is refined unless the mesh flags say.
Result<ProxyMesh> LoadOrBuildMesh(const RenderArgs& args, const Volume& volume,
                                  const std::optional<glm::dvec3>& grab_mm,
                                  const gpu::GpuContext& context, const GpuVolume& gpu_volume) {
  if (!args.mesh_json.empty()) {
    // `vpm mesh --json` writes world LPS; the scene works in physical voxel space.
    ASSIGN_OR_RETURN(const ProxyMesh world, ReadMeshJson(args.mesh_json));
    return MeshFromWorld(world, volume.geometry());
  }
  ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(args.mesh, volume));
  if (params.refine_at_mm == std::nullopt) params.refine_at_mm = grab_mm;
  ASSIGN_OR_RETURN(LatticeCostsGpu costs, LatticeCostsGpu::Create(context));
  return BuildProxyMesh(volume, params, {&gpu_volume, &costs});
}

// The grab point in physical voxel space (mm); --grab is world LPS.
Result<std::optional<glm::dvec3>> GrabPoint(const RenderArgs& args, const Volume& volume) {
  if (!args.grab.empty()) {
    ASSIGN_OR_RETURN(const glm::dvec3 world, Vec3Of(args.grab, "--grab"));
    return std::optional<glm::dvec3>(volume.geometry().WorldToPhysical(world));
  }
  if (args.grab_landmark.empty()) return std::optional<glm::dvec3>();
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == args.grab_landmark) return std::optional<glm::dvec3>(l.position_mm);
  }
  return absl::NotFoundError(
      StrCat("landmark '", args.grab_landmark, "' is not in ", volume.source()));
}

}  // namespace

// --window W L: MIP black at L - W/2, white at L + W/2.
Result<std::optional<MipWindow>> WindowOf(const std::vector<double>& w) {
  if (w.empty()) return std::optional<MipWindow>();
  if (w.size() != 2 || !std::isfinite(w[0]) || !std::isfinite(w[1]) || !(w[0] > 0.0)) {
    return absl::InvalidArgumentError("--window takes W L: a width > 0 and a level");
  }
  return std::optional<MipWindow>(MipWindow{w[1], w[0]});
}

void AddGrabFlags(CLI::App* app, RenderArgs* a) {
  app->add_option("--grab", a->grab, "grab point X Y Z (mm, world LPS, as `vpm volume info`)")
      ->expected(3);
  app->add_option("--grab-landmark", a->grab_landmark, "grab at a named landmark");
  app->add_option("--grab-rule", a->grab_rule,
                  "organ: the tissue connected to the grab point moves as a body (default); "
                  "ball: the vertices within --grab-radius (the paper's grab)")
      ->check(CLI::IsMember({"organ", "ball"}));
  app->add_option("--grab-radius", a->grab_radius,
                  "ball: handle radius in mm (default: h); organ: the organ's bound (default 80)");
  app->add_option("--pin", a->pins,
                  "hold the tissue at X Y Z (mm, world LPS) still; repeatable")
      ->expected(3)
      ->take_all();
  app->add_option("--drag", a->drag, "drag the handles by DX DY DZ mm (world LPS: +z superior)")
      ->expected(3);
  app->add_option("--pull", a->pull, "pull the handles with FX FY FZ N in total (world LPS)")
      ->expected(3);
}

Result<glm::dvec3> Vec3Of(const std::vector<double>& v, const char* flag) {
  if (v.size() != 3) return absl::InvalidArgumentError(StrCat(flag, " takes 3 numbers"));
  return glm::dvec3(v[0], v[1], v[2]);
}

Result<SceneView> MakeView(const RenderArgs& args, const Volume& volume) {
  SceneView view;
  view.camera = Camera::ForVolume(volume.geometry());
  if (!args.camera.empty()) {
    if (args.camera.size() != 3) return absl::InvalidArgumentError("--camera takes AZ EL DIST");
    Camera::Pose pose = view.camera.pose();
    pose.azimuth_deg = args.camera[0];
    pose.elevation_deg = args.camera[1];
    if (args.camera[2] > 0.0) pose.distance_mm = args.camera[2];
    view.camera.set_pose(pose);
    RETURN_IF_ERROR(view.camera.Validate());
  }
  view.mode = args.mode == "mip" ? RenderMode::kMip : RenderMode::kDvr;
  if (args.render_tf.empty()) {
    ASSIGN_OR_RETURN(view.preset, MakeRenderPreset(args.preset, volume));
  } else {
    ASSIGN_OR_RETURN(const RenderTransferFunction tf, ReadRenderTransferFunction(args.render_tf));
    ASSIGN_OR_RETURN(view.preset, RenderPresetFromTf(tf, volume));
  }
  ASSIGN_OR_RETURN(const std::optional<MipWindow> window, WindowOf(args.window));
  if (window) view.preset.mip_window = *window;
  view.quality =
      args.quality == "interactive" ? RenderQuality::kInteractive : RenderQuality::kStill;
  const std::optional<InteractiveQuality> interactive =
      InteractiveQualityNamed(args.interactive_quality);
  if (!interactive) {
    return absl::InvalidArgumentError(StrCat("--interactive-quality ", args.interactive_quality,
                                             ": auto, fast, balanced or sharp"));
  }
  view.interactive_quality = *interactive;
  if (args.size.size() != 2) return absl::InvalidArgumentError("--size takes W H");
  view.width = args.size[0];
  view.height = args.size[1];
  view.overlay = args.overlay;
  view.step_mm = args.step_mm;
  ASSIGN_OR_RETURN(const ClipChoice clip, ToClipChoice(args.clip));
  view.clip = clip.region;
  view.view_cut = clip.view_cut;
  return view;
}

namespace {

// The pins, then the grab and its drag (settled, as a session settles
// before its stills) or pull, printed as they are applied (world LPS).
Status ManipulateOffline(const RenderArgs& args, OfflineScene& scene) {
  const VolumeGeometry& geometry = scene.volume->geometry();
  for (size_t p = 0; p + 2 < args.pins.size(); p += 3) {
    const glm::dvec3 pin(args.pins[p], args.pins[p + 1], args.pins[p + 2]);  // world
    RETURN_IF_ERROR(scene.scene->Pin(geometry.WorldToPhysical(pin), 0.0).status());
    std::printf("pin at (%.1f, %.1f, %.1f) mm (LPS)\n", pin.x, pin.y, pin.z);
  }
  const std::optional<glm::dvec3>& grab = scene.grab;
  if (grab) {
    const GrabRule rule = args.grab_rule == "ball" ? GrabRule::kBall : GrabRule::kOrgan;
    ASSIGN_OR_RETURN(GrabInfo info,
                     scene.scene->Grab(GrabRequest{
                         .point_mm = *grab, .rule = rule, .radius_mm = args.grab_radius}));
    const glm::dvec3 world = geometry.PhysicalToWorld(*grab);
    std::printf("grab (%s) at (%.1f, %.1f, %.1f) mm (LPS): %zu handles%s%s\n",
                args.grab_rule.c_str(), world.x, world.y, world.z, info.handles.size(),
                info.message.empty() ? "" : "; ", info.message.c_str());
    if (!args.drag.empty()) {
      ASSIGN_OR_RETURN(glm::dvec3 offset, Vec3Of(args.drag, "--drag"));
      PrintSkeletonNearHandles(scene.mesh, info.handles, geometry.WorldVectorToPhysical(offset));
      ASSIGN_OR_RETURN(scene.step, scene.scene->Drag(geometry.WorldVectorToPhysical(offset)));
      // A drag event's FEM work is bounded (docs/FEM.md, "Per-event work bound"):
      // a long drag in one event stops short and the rest is carried. The
      // offline commands render a still, so the drag is finished first, as a
      // session does before its still frames.
      ASSIGN_OR_RETURN(SceneStepTimings settled, scene.scene->Settle(kSettleSolves));
      if (settled.max_displacement_mm > 0.0) {
        settled.fem_ms += scene.step.fem_ms;
        settled.warp_ms += scene.step.warp_ms;
        scene.step = settled;
      }
    } else if (!args.pull.empty()) {
      ASSIGN_OR_RETURN(glm::dvec3 force, Vec3Of(args.pull, "--pull"));
      ASSIGN_OR_RETURN(scene.step, scene.scene->Pull(geometry.WorldVectorToPhysical(force)));
    }
  } else if (!args.drag.empty() || !args.pull.empty()) {
    return absl::InvalidArgumentError("--drag and --pull need --grab or --grab-landmark");
  }
  return absl::OkStatus();
}

}  // namespace

Result<std::unique_ptr<OfflineScene>> PrepareOfflineScene(const RenderArgs& args) {
  auto out = std::make_unique<OfflineScene>();
  auto t0 = std::chrono::steady_clock::now();
  ProgressBar bar(StrCat("loading ", args.source), ProgressWanted(args.volume_flags.progress));
  const ProgressFn progress = bar.Reporter();
  ASSIGN_OR_RETURN(Volume volume, ReadVolumeForCli(args.source, args.volume_flags,
                                                   SubProgress(progress, 0.0, 0.8)));
  out->volume.emplace(std::move(volume));
  ASSIGN_OR_RETURN(out->grab, GrabPoint(args, *out->volume));
  out->load_ms = MsSince(t0);
  ASSIGN_OR_RETURN(out->context, gpu::GpuContext::Create({}));
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(GpuVolume gpu_volume, GpuVolume::Upload(*out->context, *out->volume,
                                                           SubProgress(progress, 0.8, 1.0)));
  bar.Finish();
  out->gpu_volume.emplace(std::move(gpu_volume));
  out->upload_ms = MsSince(t0);
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(out->mesh, LoadOrBuildMesh(args, *out->volume, out->grab, *out->context,
                                              *out->gpu_volume));
  out->mesh_ms = MsSince(t0);
  ASSIGN_OR_RETURN(out->renderer, VolumeRenderer::Create(*out->context, {}));
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(out->scene, DeformableScene::Create(*out->context, *out->volume,
                                                       *out->gpu_volume, *out->renderer,
                                                       out->mesh, {}));
  out->setup_ms = MsSince(t0);
  RETURN_IF_ERROR(ManipulateOffline(args, *out));
  return out;
}

void PrintSetupTimings(const OfflineScene& o) {
  std::printf("%-22s %9s\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n", "stage", "ms",
              "load volume", o.load_ms, "upload", o.upload_ms, "mesh", o.mesh_ms, "FEM setup",
              o.setup_ms);
}

}  // namespace vpm::cli

#include "client/cli/render_command.h"

#include <chrono>
#include <cstdio>
#include <fstream>

#include "client/cli/command_status.h"
#include "client/cli/mesh_flags.h"
#include "server/mesh/mesh_json.h"
#include "server/render/deformable_scene.h"
#include "server/render/frame_encoder.h"
#include "server/volume/read_volume.h"
#include "server/volume/write_nifti.h"

namespace vpm::cli {
namespace {

struct RenderArgs {
  std::string source, mesh_json, out, out_volume;
  MeshFlags mesh;
  std::vector<double> camera;  // AZ EL DIST
  std::string mode = "dvr", preset = "ct-soft-tissue", quality = "still";
  std::vector<double> grab, drag, pull;
  std::string grab_landmark;
  double grab_radius = 0.0;
  std::vector<int> size{512, 512};
  bool overlay = false;
  int jpeg_quality = 90;
};

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

Result<glm::dvec3> Vec3Of(const std::vector<double>& v, const char* flag) {
  if (v.size() != 3) return absl::InvalidArgumentError(StrCat(flag, " takes 3 numbers"));
  return glm::dvec3(v[0], v[1], v[2]);
}

Result<ProxyMesh> LoadOrBuildMesh(const RenderArgs& args, const Volume& volume,
                                  const gpu::GpuContext& context, const GpuVolume& gpu_volume) {
  if (!args.mesh_json.empty()) return ReadMeshJson(args.mesh_json);
  ASSIGN_OR_RETURN(MeshParams params, ToMeshParams(args.mesh, volume));
  if (params.refine_at_mm == std::nullopt && !args.grab.empty()) {
    params.refine_at_mm = glm::dvec3(args.grab[0], args.grab[1], args.grab[2]);
  }
  ASSIGN_OR_RETURN(LatticeCostsGpu costs, LatticeCostsGpu::Create(context));
  return BuildProxyMesh(volume, params, {&gpu_volume, &costs});
}

Result<std::optional<glm::dvec3>> GrabPoint(const RenderArgs& args, const Volume& volume) {
  if (!args.grab.empty()) return std::optional<glm::dvec3>(*Vec3Of(args.grab, "--grab"));
  if (args.grab_landmark.empty()) return std::optional<glm::dvec3>();
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == args.grab_landmark) return std::optional<glm::dvec3>(l.position_mm);
  }
  return absl::NotFoundError(StrCat("landmark '", args.grab_landmark, "' is not in ",
                                    volume.source()));
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
  ASSIGN_OR_RETURN(view.preset, MakeRenderPreset(args.preset, volume));
  view.quality = args.quality == "interactive" ? RenderQuality::kInteractive : RenderQuality::kStill;
  if (args.size.size() != 2) return absl::InvalidArgumentError("--size takes W H");
  view.width = args.size[0];
  view.height = args.size[1];
  view.overlay = args.overlay;
  return view;
}

Status WriteFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream file(path, std::ios::binary);
  file.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!file) return absl::PermissionDeniedError(StrCat("cannot write ", path));
  return absl::OkStatus();
}

Status Run(const RenderArgs& args) {
  const bool jpeg = args.out.ends_with(".jpg") || args.out.ends_with(".jpeg");
  if (!jpeg && !args.out.ends_with(".png")) {
    return absl::InvalidArgumentError(StrCat("--out ", args.out, ": use a .png or .jpg name"));
  }
  auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(Volume volume, ReadVolume(args.source, VolumeLimits{}));
  ASSIGN_OR_RETURN(SceneView view, MakeView(args, volume));
  ASSIGN_OR_RETURN(std::optional<glm::dvec3> grab, GrabPoint(args, volume));
  const double load_ms = MsSince(t0);
  ASSIGN_OR_RETURN(auto context, gpu::GpuContext::Create({}));
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(GpuVolume gpu_volume, GpuVolume::Upload(*context, volume));
  const double upload_ms = MsSince(t0);
  t0 = std::chrono::steady_clock::now();
  RenderArgs effective = args;
  if (grab) effective.grab = {grab->x, grab->y, grab->z};
  ASSIGN_OR_RETURN(ProxyMesh mesh, LoadOrBuildMesh(effective, volume, *context, gpu_volume));
  const double mesh_ms = MsSince(t0);
  ASSIGN_OR_RETURN(auto renderer, VolumeRenderer::Create(*context, {}));
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(auto scene,
                   DeformableScene::Create(*context, volume, gpu_volume, *renderer, mesh, {}));
  const double setup_ms = MsSince(t0);
  SceneStepTimings step;
  if (grab) {
    const double radius = args.grab_radius > 0 ? args.grab_radius : mesh.stats.h_mm;
    ASSIGN_OR_RETURN(GrabInfo info, scene->Grab(*grab, radius));
    std::printf("grab at (%.1f, %.1f, %.1f) mm, radius %.1f mm: %zu handles%s%s\n", grab->x,
                grab->y, grab->z, radius, info.handles.size(), info.message.empty() ? "" : "; ",
                info.message.c_str());
    if (!args.drag.empty()) {
      ASSIGN_OR_RETURN(glm::dvec3 offset, Vec3Of(args.drag, "--drag"));
      ASSIGN_OR_RETURN(step, scene->Drag(offset));
    } else if (!args.pull.empty()) {
      ASSIGN_OR_RETURN(glm::dvec3 force, Vec3Of(args.pull, "--pull"));
      ASSIGN_OR_RETURN(step, scene->Pull(force));
    }
  } else if (!args.drag.empty() || !args.pull.empty()) {
    return absl::InvalidArgumentError("--drag and --pull need --grab or --grab-landmark");
  }
  ASSIGN_OR_RETURN(Frame frame, scene->Render(view));
  t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                   jpeg ? EncodeJpeg(frame.rgba, frame.width, frame.height, args.jpeg_quality)
                        : EncodePng(frame.rgba, frame.width, frame.height));
  const double encode_ms = MsSince(t0);
  RETURN_IF_ERROR(WriteFile(args.out, bytes));
  std::printf("mesh %zu vertices, %zu tets; max displacement %.2f mm, inverted tets %lld\n",
              mesh.vertices.size(), mesh.tets.size(), step.max_displacement_mm,
              static_cast<long long>(step.inverted_tets));
  std::printf("%-22s %9s\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n", "stage", "ms",
              "load volume", load_ms, "upload", upload_ms, "mesh", mesh_ms, "FEM setup",
              setup_ms);
  std::printf("%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n", "FEM solve", step.fem_ms,
              "backward map", step.warp_ms, "render (GPU)", frame.timings.render_ms, "encode",
              encode_ms);
  std::printf("wrote %s (%dx%d, %zu bytes)\n", args.out.c_str(), frame.width, frame.height,
              bytes.size());
  if (!args.out_volume.empty()) {
    ASSIGN_OR_RETURN(Volume warped, scene->WarpedVolume());
    RETURN_IF_ERROR(WriteNifti(warped, args.out_volume));
    std::printf("wrote %s (deformed volume, source geometry)\n", args.out_volume.c_str());
  }
  return absl::OkStatus();
}

}  // namespace

void AddRenderCommand(CLI::App& app, int* exit_code) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render one frame, optionally after a drag");
  cmd->add_option("--volume", a->source, "a file, a DICOM folder or phantom:NAME")->required();
  cmd->add_option("--mesh-json", a->mesh_json, "a mesh written by `vpm mesh --json`");
  AddMeshFlags(cmd, &a->mesh);
  cmd->add_option("--camera", a->camera,
                  "AZ EL DIST: degrees from the anterior view, DIST mm (0: fit)")->expected(3);
  cmd->add_option("--mode", a->mode, "dvr or mip")->check(CLI::IsMember({"dvr", "mip"}))
      ->capture_default_str();
  cmd->add_option("--preset", a->preset, "render preset: ct-soft-tissue, ct-bone, ct-vessels, mri-t1")
      ->capture_default_str();
  cmd->add_option("--quality", a->quality, "still or interactive")
      ->check(CLI::IsMember({"still", "interactive"}))->capture_default_str();
  cmd->add_option("--grab", a->grab, "grab point X Y Z (mm, physical voxel space)")->expected(3);
  cmd->add_option("--grab-landmark", a->grab_landmark, "grab at a named landmark");
  cmd->add_option("--grab-radius", a->grab_radius, "handle radius in mm (default: h)");
  cmd->add_option("--drag", a->drag, "drag the handles by DX DY DZ mm")->expected(3);
  cmd->add_option("--pull", a->pull, "pull the handles with FX FY FZ N in total")->expected(3);
  cmd->add_option("--size", a->size, "W H pixels")->expected(2)->capture_default_str();
  cmd->add_flag("--overlay", a->overlay, "draw the proxy mesh: deformable yellow, hard blue");
  cmd->add_option("--jpeg-quality", a->jpeg_quality, "1..100")->capture_default_str();
  cmd->add_option("--out", a->out, "frame.png or frame.jpg")->required();
  cmd->add_option("--out-volume", a->out_volume, "also write the deformed volume (NIfTI)");
  cmd->callback([a, exit_code] { *exit_code = ExitWith(Run(*a)); });
}

}  // namespace vpm::cli

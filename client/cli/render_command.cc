#include "client/cli/render_command.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "client/cli/clip_flags.h"
#include "client/common/command_status.h"
#include "client/cli/mesh_flags.h"
#include "client/cli/offline_scene.h"
#include "client/cli/remote_pipeline.h"
#include "proto/enum_names.h"
#include "proto/render_tf_convert.h"
#include "proto/vec3_convert.h"
#include "server/common/clock.h"
#include "server/common/write_file.h"
#include "server/mesh/mesh_json.h"
#include "server/scene/deformable_scene.h"
#include "server/raycast/frame_encoder.h"
#include "server/io/read_render_transfer_function.h"
#include "server/io/read_volume.h"
#include "server/raycast/render_preset_from_tf.h"
#include "server/io/write_nifti.h"
#include "server/io/write_displacement_field.h"

namespace vpm::cli {
namespace {

Result<bool> IsJpegName(const std::string& out) {
  const bool jpeg = out.ends_with(".jpg") || out.ends_with(".jpeg");
  if (!jpeg && !out.ends_with(".png")) {
    return absl::InvalidArgumentError(StrCat("--out ", out, ": use a .png or .jpg name"));
  }
  return jpeg;
}

// --out-volume and --out-displacement, through the exact map of the scene's
// deformation on the source grid.
Status WriteDeformation(const RenderArgs& args, OfflineScene& offline) {
  if (!args.out_volume.empty()) {
    ASSIGN_OR_RETURN(Volume warped, offline.scene->WarpedVolume());
    RETURN_IF_ERROR(WriteNifti(warped, args.out_volume));
    std::printf("wrote %s (deformed volume, source geometry)\n", args.out_volume.c_str());
  }
  if (!args.out_displacement.empty()) {
    ASSIGN_OR_RETURN(const std::vector<glm::vec3> field, offline.scene->DisplacementField());
    RETURN_IF_ERROR(
        WriteDisplacementField(offline.volume->geometry(), field, args.out_displacement));
    std::printf("wrote %s (displacement field, world LPS mm, source grid)\n",
                args.out_displacement.c_str());
  }
  return absl::OkStatus();
}

Status RunOffline(const RenderArgs& args) {
  ASSIGN_OR_RETURN(const bool jpeg, IsJpegName(args.out));
  ASSIGN_OR_RETURN(std::unique_ptr<OfflineScene> offline, PrepareOfflineScene(args));
  ASSIGN_OR_RETURN(SceneView view, MakeView(args, *offline->volume));
  DeformableScene* scene = offline->scene.get();
  const ProxyMesh& mesh = offline->mesh;
  const SceneStepTimings& step = offline->step;
  ASSIGN_OR_RETURN(Frame frame, scene->Render(view));
  const auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                   jpeg ? EncodeJpeg(frame.rgba, frame.width, frame.height, args.jpeg_quality)
                        : EncodePng(frame.rgba, frame.width, frame.height));
  const double encode_ms = MsSince(t0);
  RETURN_IF_ERROR(WriteFile(
      args.out, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size())));
  std::printf(
      "mesh %zu vertices, %zu tets; max displacement %.2f mm, inverted tets %lld, lag %.2f mm\n",
      mesh.vertices.size(), mesh.tets.size(), step.max_displacement_mm,
      static_cast<long long>(step.inverted_tets), step.lag_mm);
  if (offline->grab) {
    if (auto at = view.camera.Project(*offline->grab, frame.width, frame.height)) {
      std::printf("grab point at pixel (%.0f, %.0f)\n", at->x, at->y);
    }
  }
  PrintSetupTimings(*offline);
  std::printf("%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n", "FEM solve", step.fem_ms,
              "backward map", step.warp_ms, "render (GPU)", frame.timings.render_ms, "encode",
              encode_ms);
  std::printf("wrote %s (%dx%d, %zu bytes)\n", args.out.c_str(), frame.width, frame.height,
              bytes.size());
  return WriteDeformation(args, *offline);
}

// Closes a server session when it goes out of scope (errors ignored: the
// server evicts idle sessions anyway).
class SessionCloser {
 public:
  SessionCloser(const ServerConnection& server, std::string id) : server_(server), id_(id) {}
  ~SessionCloser() { server_.CloseSessionQuietly(id_); }
  SessionCloser(const SessionCloser&) = delete;
  SessionCloser& operator=(const SessionCloser&) = delete;

 private:
  const ServerConnection& server_;
  std::string id_;
};

Result<v3::ManipulateResponse> Manipulate(const ServerConnection& server,
                                          const std::string& session, v3::ClientEvent event) {
  v3::ManipulateRequest request;
  request.set_session_id(session);
  *request.mutable_event() = std::move(event);
  v3::ManipulateResponse response;
  RETURN_IF_ERROR(FromGrpc(server.stub().Manipulate(server.Context().get(), request, &response)));
  return response;
}

// The flags RunOnServer refuses: those only the offline render reads, and
// malformed ones.
Status CheckServerRenderArgs(const RenderArgs& args) {
  if (!args.mesh_json.empty()) {
    return absl::InvalidArgumentError(
        "--mesh-json is offline only: with --server the server builds the mesh from the mesh "
        "flags");
  }
  if (!args.out_volume.empty()) return absl::InvalidArgumentError("--out-volume is offline only");
  if (!args.out_displacement.empty()) {
    return absl::InvalidArgumentError("--out-displacement is offline only");
  }
  if (args.quality != "still") {
    return absl::InvalidArgumentError(
        "--quality interactive is offline only (Render is a still frame)");
  }
  if (args.size.size() != 2) return absl::InvalidArgumentError("--size takes W H");
  if (args.step_mm != 0.0) {
    return absl::InvalidArgumentError("--step is offline only (the server picks the step)");
  }
  if (!args.camera.empty() && args.camera.size() != 3) {
    return absl::InvalidArgumentError("--camera takes AZ EL DIST");
  }
  if (args.grab.empty() && args.grab_landmark.empty() &&
      (!args.drag.empty() || !args.pull.empty())) {
    return absl::InvalidArgumentError("--drag and --pull need --grab or --grab-landmark");
  }
  return absl::OkStatus();
}

// The volume, mesh and session a server render works on.
struct ServerScene {
  v3::VolumeInfo volume;
  v3::MeshInfo mesh;
  v3::SessionInfo session;
  std::vector<double> grab;  // mm, empty: no grab
};

// LoadVolume, BuildMesh (refined at the grab point, as offline) and
// OpenSession.
Result<ServerScene> OpenServerScene(const ServerConnection& server, const RenderArgs& args) {
  ServerScene scene;
  ASSIGN_OR_RETURN(scene.volume, LoadVolumeOnServer(server, args.source));
  scene.grab = args.grab;
  if (!args.grab_landmark.empty()) {
    ASSIGN_OR_RETURN(glm::dvec3 at, FindLandmark(scene.volume, args.grab_landmark));
    scene.grab = {at.x, at.y, at.z};
  }
  MeshFlags mesh_flags = args.mesh;
  if (!scene.grab.empty() && mesh_flags.refine_at.empty() &&
      mesh_flags.refine_at_landmark.empty()) {
    mesh_flags.refine_at = scene.grab;
  }
  v3::BuildMeshRequest build;
  build.set_volume_id(scene.volume.volume_id());
  ASSIGN_OR_RETURN(*build.mutable_params(), ToProtoMeshParams(mesh_flags, scene.volume));
  RETURN_IF_ERROR(FromGrpc(server.stub().BuildMesh(server.Context().get(), build, &scene.mesh)));
  v3::OpenSessionRequest open;
  open.set_volume_id(scene.volume.volume_id());
  open.set_mesh_id(scene.mesh.mesh_id());
  RETURN_IF_ERROR(
      FromGrpc(server.stub().OpenSession(server.Context().get(), open, &scene.session)));
  return scene;
}

// The pins, then the grab and its drag or pull, as Manipulate events.
Status ManipulateOnServer(const ServerConnection& server, const std::string& session,
                          const std::vector<double>& grab, const RenderArgs& args) {
  for (size_t p = 0; p + 2 < args.pins.size(); p += 3) {
    v3::ClientEvent pin;
    *pin.mutable_pin()->mutable_point_mm() =
        ToProto(glm::dvec3(args.pins[p], args.pins[p + 1], args.pins[p + 2]));
    RETURN_IF_ERROR(Manipulate(server, session, pin).status());
  }
  if (grab.empty()) return absl::OkStatus();
  v3::ClientEvent event;
  ASSIGN_OR_RETURN(const glm::dvec3 grab_mm, Vec3Of(grab, "--grab"));
  *event.mutable_grab()->mutable_point_mm() = ToProto(grab_mm);
  event.mutable_grab()->set_radius_mm(args.grab_radius);
  event.mutable_grab()->set_rule(args.grab_rule == "ball" ? v3::GRAB_RULE_BALL
                                                          : v3::GRAB_RULE_ORGAN);
  RETURN_IF_ERROR(Manipulate(server, session, event).status());
  event.Clear();
  if (!args.drag.empty()) {
    ASSIGN_OR_RETURN(const glm::dvec3 offset, Vec3Of(args.drag, "--drag"));
    *event.mutable_drag()->mutable_offset_mm() = ToProto(offset);
  }
  if (!args.pull.empty()) {
    ASSIGN_OR_RETURN(const glm::dvec3 force, Vec3Of(args.pull, "--pull"));
    *event.mutable_pull()->mutable_force_n() = ToProto(force);
  }
  if (event.event_case() == v3::ClientEvent::EVENT_NOT_SET) return absl::OkStatus();
  return Manipulate(server, session, event).status();
}

// The Render request for the flags: camera, mode, preset or transfer
// function, window, size, overlay, encoding and clip.
Result<v3::RenderRequest> ServerRenderRequest(const std::string& session, const RenderArgs& args,
                                              bool jpeg) {
  v3::RenderRequest render;
  render.set_session_id(session);
  if (!args.camera.empty()) {
    render.mutable_camera()->set_azimuth_deg(args.camera[0]);
    render.mutable_camera()->set_elevation_deg(args.camera[1]);
    render.mutable_camera()->set_distance_mm(args.camera[2]);
  }
  v3::RenderSettings* settings = render.mutable_settings();
  const auto mode = RenderModeFromName(args.mode);
  if (!mode) return absl::InvalidArgumentError(StrCat("--mode: '", args.mode, "' is not dvr or mip"));
  settings->set_mode(*mode);
  if (args.render_tf.empty()) {
    settings->set_preset(args.preset);
  } else {
    ASSIGN_OR_RETURN(const RenderTransferFunction tf, ReadRenderTransferFunction(args.render_tf));
    *settings->mutable_render_tf() = ToProto(tf);
  }
  ASSIGN_OR_RETURN(const std::optional<MipWindow> window, WindowOf(args.window));
  if (window) {
    settings->mutable_mip_window()->set_width(window->width);
    settings->mutable_mip_window()->set_level(window->level);
  }
  settings->set_width(args.size[0]);
  settings->set_height(args.size[1]);
  settings->set_overlay(args.overlay);
  settings->set_encoding(jpeg ? v3::ENCODING_JPEG : v3::ENCODING_PNG);
  settings->set_jpeg_quality(args.jpeg_quality);
  ASSIGN_OR_RETURN(const ClipChoice clip, ToClipChoice(args.clip));
  FillClipSettings(clip, settings);
  return render;
}

// What a server render prints: the ids, the settled state, the server's
// stage timings and the file written.
void PrintServerRender(const ServerFlags& flags, const ServerScene& scene, const v3::Frame& frame,
                       const std::string& out) {
  std::printf("server %s: volume %s, mesh %s (%lld vertices, %lld tets), session %s\n",
              flags.address.c_str(), scene.volume.volume_id().c_str(), scene.mesh.mesh_id().c_str(),
              static_cast<long long>(scene.mesh.stats().vertices()),
              static_cast<long long>(scene.mesh.stats().tets()),
              scene.session.session_id().c_str());
  // The still's state: the drag settled (the server finishes it first).
  std::printf("max displacement %.2f mm, inverted tets %lld, lag %.2f mm\n",
              frame.max_displacement_mm(), static_cast<long long>(frame.inverted_tets()),
              frame.lag_mm());
  const v3::StageTimings& t = frame.timings();
  std::printf("%-22s %9s\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n%-22s %9.1f\n", "stage (server)",
              "ms", "render (GPU)", t.render_ms(), "encode", t.encode_ms(), "queue", t.queue_ms(),
              "total", t.total_ms());
  std::printf("wrote %s (%dx%d, %zu bytes)\n", out.c_str(), frame.width(), frame.height(),
              frame.image().size());
}

// The same frame rendered by a vpm-server: LoadVolume, BuildMesh (refined
// at the grab point, as offline), OpenSession, Manipulate, Render.
Status RunOnServer(const ServerFlags& flags, const RenderArgs& args) {
  ASSIGN_OR_RETURN(const bool jpeg, IsJpegName(args.out));
  RETURN_IF_ERROR(CheckServerRenderArgs(args));
  ASSIGN_OR_RETURN(ServerConnection server, ServerConnection::Connect(flags));
  ASSIGN_OR_RETURN(const ServerScene scene, OpenServerScene(server, args));
  SessionCloser closer(server, scene.session.session_id());
  RETURN_IF_ERROR(ManipulateOnServer(server, scene.session.session_id(), scene.grab, args));
  ASSIGN_OR_RETURN(const v3::RenderRequest render,
                   ServerRenderRequest(scene.session.session_id(), args, jpeg));
  v3::Frame frame;
  RETURN_IF_ERROR(FromGrpc(server.stub().Render(server.Context().get(), render, &frame)));
  RETURN_IF_ERROR(WriteFile(args.out, frame.image()));
  PrintServerRender(flags, scene, frame, args.out);
  return absl::OkStatus();
}

}  // namespace

void AddRenderCommand(CLI::App& app, const ServerFlags* server, int* exit_code) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render", "Render one frame, optionally after a drag (offline, or on --server)");
  cmd->add_option("--volume", a->source, "a file, a DICOM folder or phantom:NAME")->required();
  cmd->add_option("--mesh-json", a->mesh_json, "a mesh written by `vpm mesh --json`");
  AddMeshFlags(cmd, &a->mesh);
  AddVolumeFlags(cmd, &a->volume_flags);
  cmd->add_option("--camera", a->camera,
                  "AZ EL DIST: degrees from the anterior view, DIST mm (0: fit)")
      ->expected(3);
  cmd->add_option("--mode", a->mode, "dvr or mip")
      ->check(CLI::IsMember({"dvr", "mip"}))
      ->capture_default_str();
  cmd->add_option("--preset", a->preset,
                  "render preset: auto (ct-soft-tissue on CT, mri-t1 otherwise), ct-soft-tissue, "
                  "ct-bone, ct-vessels, mri-t1, or Slicer's "
                  "CT-AAA, CT-Bone, CT-Muscle, CT-Chest-Contrast-Enhanced, CT-Soft-Tissue, "
                  "MR-Default")
      ->capture_default_str();
  cmd->add_option("--render-tf", a->render_tf,
                  "DVR transfer function file (overrides --preset): ParaView FILE.json[#NAME] "
                  "or 3D Slicer FILE.vp");
  cmd->add_option("--window", a->window,
                  "MIP window W L: black at L - W/2, white at L + W/2 (default: the volume's "
                  "1st..99.5th percentile, above air for CT)")
      ->expected(2);
  cmd->add_option("--step", a->step_mm,
                  "sample step along the rays, mm (0: the quality's default: a still DVR "
                  "frame the preset's factor of the smallest spacing; offline only)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--quality", a->quality, "still or interactive")
      ->check(CLI::IsMember({"still", "interactive"}))
      ->capture_default_str();
  cmd->add_option("--interactive-quality", a->interactive_quality,
                  "with --quality interactive: auto (sharp on a discrete GPU, else fast), "
                  "fast, balanced or sharp (docs/RENDERING.md, \"Interactive quality\"; "
                  "offline only)")
      ->check(CLI::IsMember({"auto", "fast", "balanced", "sharp"}))
      ->capture_default_str();
  AddGrabFlags(cmd, a.get());
  cmd->add_option("--size", a->size, "W H pixels")->expected(2)->capture_default_str();
  cmd->add_flag("--overlay", a->overlay, "draw the proxy mesh: deformable yellow, hard blue");
  AddClipFlags(cmd, &a->clip);
  cmd->add_option("--jpeg-quality", a->jpeg_quality, "1..100")->capture_default_str();
  cmd->add_option("--out", a->out, "frame.png or frame.jpg")->required();
  cmd->add_option("--out-volume", a->out_volume, "also write the deformed volume (NIfTI)");
  cmd->add_option("--out-displacement", a->out_displacement,
                  "also write the displacement field (.mha or .nrrd; world LPS mm on the source "
                  "grid, the grid transform 3D Slicer and ITK apply)");
  cmd->callback([server, a, exit_code] {
    *exit_code = ExitWith(server->address.empty() ? RunOffline(*a) : RunOnServer(*server, *a));
  });
}

}  // namespace vpm::cli

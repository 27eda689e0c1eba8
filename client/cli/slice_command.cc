#include "client/cli/slice_command.h"

#include <cctype>
#include <cstdio>
#include <memory>
#include <string_view>

#include "client/common/command_status.h"
#include "client/cli/offline_scene.h"
#include "client/cli/server_flags.h"
#include "proto/enum_names.h"
#include "proto/vec3_convert.h"
#include "server/common/write_file.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::cli {
namespace {

struct SliceArgs {
  RenderArgs scene;
  std::string session_id;  // with --server: RenderSlice on this session
  std::string plane = "axial";
  std::vector<double> at;  // empty or one number (mm, world)
  std::string at_landmark;
  std::vector<double> normal;  // oblique: NX NY NZ (world)
  std::vector<double> window;  // empty or W L
  double pixel_mm = 0.0;
};

// The world point the plane passes through: --at-landmark, else the grabbed
// tissue where the drag moved it, else the volume's centre.
Result<glm::dvec3> PlanePoint(const SliceArgs& args, const OfflineScene& offline) {
  const VolumeGeometry& g = offline.volume->geometry();
  if (!args.at_landmark.empty()) {
    for (const Landmark& l : offline.volume->landmarks()) {
      if (l.name == args.at_landmark) return g.PhysicalToWorld(l.position_mm);
    }
    return absl::NotFoundError(StrCat("landmark '", args.at_landmark, "' is not in ",
                                      offline.volume->source()));
  }
  if (const auto grabbed = offline.scene->GrabbedTissueMm()) return g.PhysicalToWorld(*grabbed);
  return g.PhysicalToWorld(0.5 * g.extent_mm());
}

Result<SlicePlane> MakePlane(const SliceArgs& args, const OfflineScene& offline) {
  SlicePlane plane;
  ASSIGN_OR_RETURN(plane.orientation, SliceOrientationFromName(args.plane));
  if (!args.at.empty() && !args.at_landmark.empty()) {
    return absl::InvalidArgumentError("give --at or --at-landmark, not both");
  }
  ASSIGN_OR_RETURN(const glm::dvec3 point, PlanePoint(args, offline));
  switch (plane.orientation) {
    case SliceOrientation::kAxial: plane.at_mm = point.z; break;
    case SliceOrientation::kCoronal: plane.at_mm = point.y; break;
    case SliceOrientation::kSagittal: plane.at_mm = point.x; break;
    case SliceOrientation::kOblique:
      if (args.normal.size() != 3) {
        return absl::InvalidArgumentError("--plane oblique needs --normal NX NY NZ (world)");
      }
      if (!args.at.empty()) {
        return absl::InvalidArgumentError(
            "--at places named planes; an oblique plane passes through --at-landmark or the grab");
      }
      plane.point_mm = point;
      plane.normal = glm::dvec3(args.normal[0], args.normal[1], args.normal[2]);
      break;
  }
  if (!args.at.empty()) plane.at_mm = args.at[0];
  return plane;
}

Status RunSlice(const SliceArgs& args) {
  const std::string& out = args.scene.out;
  const bool jpeg = out.ends_with(".jpg") || out.ends_with(".jpeg");
  if (!jpeg && !out.ends_with(".png")) {
    return absl::InvalidArgumentError(StrCat("--out ", out, ": use a .png or .jpg name"));
  }
  ASSIGN_OR_RETURN(std::unique_ptr<OfflineScene> offline, PrepareOfflineScene(args.scene));
  SliceView view;
  ASSIGN_OR_RETURN(view.plane, MakePlane(args, *offline));
  view.pixel_mm = args.pixel_mm;
  view.overlay = args.scene.overlay;
  ASSIGN_OR_RETURN(view.window, WindowOf(args.window));
  ASSIGN_OR_RETURN(SliceFrame frame, offline->scene->RenderSlice(view));
  const int w = frame.grid.width, h = frame.grid.height;
  ASSIGN_OR_RETURN(std::vector<uint8_t> bytes,
                   jpeg ? EncodeJpeg(frame.rgba, w, h, args.scene.jpeg_quality)
                        : EncodePng(frame.rgba, w, h));
  RETURN_IF_ERROR(
      WriteFile(out, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size())));
  const glm::dvec3& n = frame.grid.world_normal;
  std::printf("%s slice, normal (%.3f, %.3f, %.3f), %.3f mm from the world origin; window W %.0f L %.0f\n",
              std::string(SliceOrientationName(view.plane.orientation)).c_str(), n.x, n.y, n.z,
              glm::dot(n, frame.grid.world_origin_mm), frame.window.width, frame.window.level);
  std::printf("mesh %zu vertices, %zu tets; max displacement %.2f mm, inverted tets %lld",
              offline->mesh.vertices.size(), offline->mesh.tets.size(),
              offline->step.max_displacement_mm, static_cast<long long>(offline->step.inverted_tets));
  if (frame.cut_tets >= 0) std::printf("; the plane cuts %lld tets", static_cast<long long>(frame.cut_tets));
  std::printf("\n");
  PrintSetupTimings(*offline);
  std::printf("%-22s %9.1f\n", "slice (GPU)", frame.gpu_ms);
  std::printf("wrote %s (%dx%d, %.3f mm per pixel, %zu bytes)\n", out.c_str(), w, h,
              frame.grid.pixel_mm, bytes.size());
  return absl::OkStatus();
}

// With --server: RenderSlice of a session's current deformation; the plane
// as offline (without --at: through the grabbed tissue, else the centre).
Status RunRemoteSlice(const SliceArgs& args, const ServerConnection& server) {
  if (args.session_id.empty()) {
    return absl::InvalidArgumentError("with --server, slice needs --session ID");
  }
  if (!args.scene.source.empty()) {
    return absl::InvalidArgumentError(
        "with --server, slice shows a session (--session): --volume is offline only");
  }
  v3::RenderSliceRequest request;
  request.set_session_id(args.session_id);
  v3::SliceSpec* spec = request.mutable_slice();
  std::string enum_name = "SLICE_ORIENTATION_" + args.plane;
  for (char& c : enum_name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  v3::SliceOrientation orientation = v3::SLICE_ORIENTATION_UNSPECIFIED;
  if (!v3::SliceOrientation_Parse(enum_name, &orientation)) {
    return absl::InvalidArgumentError(StrCat("--plane ", args.plane, ": not a plane"));
  }
  spec->set_orientation(orientation);
  if (!args.at.empty()) spec->set_at_mm(args.at[0]);
  spec->set_at_landmark(args.at_landmark);
  if (args.normal.size() == 3) {
    *spec->mutable_normal() = ToProto(glm::dvec3(args.normal[0], args.normal[1], args.normal[2]));
  }
  if (args.window.size() == 2) {
    spec->mutable_window()->set_width(args.window[0]);
    spec->mutable_window()->set_level(args.window[1]);
  }
  spec->set_pixel_mm(args.pixel_mm);
  spec->set_overlay(args.scene.overlay);
  request.set_encoding(EncodingForFile(args.scene.out));
  request.set_jpeg_quality(args.scene.jpeg_quality);
  v3::Frame frame;
  RETURN_IF_ERROR(FromGrpc(server.stub().RenderSlice(server.Context().get(), request, &frame)));
  RETURN_IF_ERROR(WriteFile(args.scene.out, frame.image()));
  const v3::SliceGeometry& g = frame.slice();
  std::printf("%s slice at %.3f mm along (%.3f, %.3f, %.3f); window W %.0f L %.0f",
              args.plane.c_str(), g.offset_mm(), g.world_normal().x(), g.world_normal().y(),
              g.world_normal().z(), g.window().width(), g.window().level());
  if (g.cut_tets() >= 0) std::printf("; the plane cuts %lld tets", static_cast<long long>(g.cut_tets()));
  std::printf("\nwrote %s (%dx%d, %.3f mm per pixel, %zu bytes; render %.1f ms)\n",
              args.scene.out.c_str(), frame.width(), frame.height(), g.pixel_mm(),
              frame.image().size(), frame.timings().render_ms());
  return absl::OkStatus();
}

}  // namespace

void AddSliceCommand(CLI::App& app, const ServerFlags* server_flags, int* exit_code) {
  auto a = std::make_shared<SliceArgs>();
  CLI::App* cmd = app.add_subcommand(
      "slice", "A slice of the volume, optionally after a drag (axial, coronal, sagittal, oblique)");
  cmd->add_option("--volume", a->scene.source,
                  "a file, a DICOM folder or phantom:NAME (offline; required without --server)");
  cmd->add_option("--session", a->session_id, "with --server: slice this session (RenderSlice)");
  cmd->add_option("--mesh-json", a->scene.mesh_json, "a mesh written by `vpm mesh --json`");
  AddMeshFlags(cmd, &a->scene.mesh);
  AddVolumeFlags(cmd, &a->scene.volume_flags);
  AddGrabFlags(cmd, &a->scene);
  cmd->add_option("--plane", a->plane, "axial, coronal, sagittal or oblique")
      ->check(CLI::IsMember({"axial", "coronal", "sagittal", "oblique"}))
      ->capture_default_str();
  cmd->add_option("--at", a->at,
                  "world coordinate along the plane's normal axis, mm (axial: z, coronal: y, "
                  "sagittal: x; default: through the dragged grab point or the centre)")
      ->expected(1);
  cmd->add_option("--at-landmark", a->at_landmark, "through a named landmark");
  cmd->add_option("--normal", a->normal, "oblique plane's normal NX NY NZ (world LPS)")->expected(3);
  cmd->add_option("--window", a->window,
                  "W L: values L - W/2 .. L + W/2 black to white (default: CT W 400 L 40, "
                  "else the 1st..99th percentile)")
      ->expected(2);
  cmd->add_option("--pixel", a->pixel_mm, "pixel size in mm (default: the smallest spacing)");
  cmd->add_flag("--overlay", a->scene.overlay,
                "outline the tets the plane cuts and mark the grabbed tissue");
  cmd->add_option("--jpeg-quality", a->scene.jpeg_quality, "1..100")->capture_default_str();
  cmd->add_option("--out", a->scene.out, "slice.png or slice.jpg")->required();
  cmd->callback([a, server_flags, exit_code] {
    if (!server_flags->address.empty()) {
      WithServer(server_flags, exit_code,
                 [a](const ServerConnection& s) { return RunRemoteSlice(*a, s); })();
      return;
    }
    if (a->scene.source.empty()) {
      *exit_code = ExitWith(absl::InvalidArgumentError(
          "slice needs --volume SOURCE (or --server ADDR --session ID)"));
      return;
    }
    *exit_code = ExitWith(RunSlice(*a));
  });
}

}  // namespace vpm::cli

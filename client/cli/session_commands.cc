#include "client/cli/session_commands.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "client/common/proto_json.h"
#include "proto/enum_names.h"
#include "client/cli/server_flags.h"
#include "server/common/write_file.h"

namespace vpm::cli {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// What the session commands' flags fill.
struct SessionArgs {
  std::string volume_id, mesh_id, session_id, out, out_dir, user;
  bool revoke = false;
  std::vector<double> camera, grab, drag, pull, pin;
  std::vector<int> size{512, 512};
  bool release = false, keep = false, reset = false;
  std::string grab_rule = "organ";
  double radius_mm = 0.0;
  int frames = 10;
};

// session open, list and close; returns the session command.
CLI::App* AddSessionOpenListClose(CLI::App& app, const ServerFlags* flags, int* exit_code,
                                  std::shared_ptr<SessionArgs> a) {
  CLI::App* session = app.add_subcommand("session", "server: sessions");
  session->require_subcommand(1);
  CLI::App* open = session->add_subcommand("open", "OpenSession");
  open->add_option("--volume-id", a->volume_id);
  open->add_option("--mesh-id", a->mesh_id, "empty: a mesh with default parameters");
  open->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::OpenSessionRequest request;
    request.set_volume_id(a->volume_id);
    request.set_mesh_id(a->mesh_id);
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenSession(s.Context().get(), request, &info)));
    PrintJson(SessionJson(info));
    return absl::OkStatus();
  }));
  session->add_subcommand("list", "ListSessions")
      ->callback(WithServer(flags, exit_code, [](const ServerConnection& s) -> Status {
        v3::ListSessionsResponse response;
        RETURN_IF_ERROR(FromGrpc(s.stub().ListSessions(s.Context().get(), {}, &response)));
        json j = json::array();
        for (const auto& x : response.sessions()) j.push_back(SessionJson(x));
        PrintJson(j);
        return absl::OkStatus();
      }));
  CLI::App* close = session->add_subcommand("close", "CloseSession");
  close->add_option("ID", a->session_id)->required();
  close->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::CloseSessionRequest request;
    request.set_session_id(a->session_id);
    v3::CloseSessionResponse response;
    return FromGrpc(s.stub().CloseSession(s.Context().get(), request, &response));
  }));
  return session;
}

// session get and share.
void AddSessionGetShare(CLI::App* session, const ServerFlags* flags, int* exit_code,
                        std::shared_ptr<SessionArgs> a) {
  CLI::App* get = session->add_subcommand("get", "GetSession");
  get->add_option("ID", a->session_id)->required();
  get->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::GetSessionRequest request;
    request.set_session_id(a->session_id);
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetSession(s.Context().get(), request, &info)));
    PrintJson(SessionJson(info));
    return absl::OkStatus();
  }));
  CLI::App* share = session->add_subcommand(
      "share", "ShareSession: let another user watch the session (never deform it)");
  share->add_option("ID", a->session_id)->required();
  share->add_option("--with", a->user, "the user's name on the server")->required();
  share->add_flag("--revoke", a->revoke, "no longer let that user watch");
  share->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::ShareSessionRequest request;
    request.set_session_id(a->session_id);
    request.set_user(a->user);
    request.set_revoke(a->revoke);
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().ShareSession(s.Context().get(), request, &info)));
    PrintJson(SessionJson(info));
    return absl::OkStatus();
  }));
}

// snapshot: one still frame of a session (Render).
void AddSnapshotCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                        std::shared_ptr<SessionArgs> a) {
  CLI::App* snapshot = app.add_subcommand("snapshot", "server: Render one still frame");
  snapshot->add_option("--session", a->session_id)->required();
  snapshot->add_option("--camera", a->camera, "AZ EL DIST (DIST 0: fit)")->expected(3);
  snapshot->add_option("--size", a->size, "W H")->expected(2);
  snapshot->add_option("--out", a->out, "frame.jpg or frame.png")->required();
  snapshot->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::RenderRequest request;
    request.set_session_id(a->session_id);
    if (a->camera.size() == 3) {
      request.mutable_camera()->set_azimuth_deg(a->camera[0]);
      request.mutable_camera()->set_elevation_deg(a->camera[1]);
      request.mutable_camera()->set_distance_mm(a->camera[2]);
    }
    request.mutable_settings()->set_width(a->size[0]);
    request.mutable_settings()->set_height(a->size[1]);
    request.mutable_settings()->set_encoding(EncodingForFile(a->out));
    v3::Frame frame;
    RETURN_IF_ERROR(FromGrpc(s.stub().Render(s.Context().get(), request, &frame)));
    RETURN_IF_ERROR(WriteFile(a->out, frame.image()));
    std::printf("wrote %s (%dx%d, %zu bytes; render %.1f ms, encode %.1f ms)\n", a->out.c_str(),
                frame.width(), frame.height(), frame.image().size(), frame.timings().render_ms(),
                frame.timings().encode_ms());
    return absl::OkStatus();
  }));
}

// manipulate: one event (Manipulate).
void AddManipulateCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                          std::shared_ptr<SessionArgs> a) {
  CLI::App* manipulate = app.add_subcommand("manipulate", "server: Manipulate (one event)");
  manipulate->add_option("--session", a->session_id)->required();
  manipulate->add_option("--grab", a->grab, "X Y Z mm")->expected(3);
  manipulate->add_option("--drag", a->drag, "DX DY DZ mm")->expected(3);
  manipulate->add_option("--pull", a->pull, "FX FY FZ N")->expected(3);
  manipulate->add_option("--grab-rule", a->grab_rule, "organ (default) or ball")
      ->check(CLI::IsMember({"organ", "ball"}));
  manipulate->add_option("--radius", a->radius_mm,
                         "grab: the organ's bound or the ball's radius; pin: its radius (mm)");
  manipulate->add_option("--pin", a->pin, "hold the tissue at X Y Z mm still")->expected(3);
  manipulate->add_flag("--release", a->release);
  manipulate->add_flag("--keep", a->keep, "with --release: the drag stays");
  manipulate->add_flag("--reset", a->reset, "back to rest: drops the grab, kept drags and pins");
  manipulate->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::ManipulateRequest request;
    request.set_session_id(a->session_id);
    v3::ClientEvent* e = request.mutable_event();
    e->set_sequence(1);
    auto set = [](v3::Vec3* v, const std::vector<double>& x) {
      v->set_x(x[0]);
      v->set_y(x[1]);
      v->set_z(x[2]);
    };
    if (a->grab.size() == 3) {
      set(e->mutable_grab()->mutable_point_mm(), a->grab);
      e->mutable_grab()->set_radius_mm(a->radius_mm);
      e->mutable_grab()->set_rule(a->grab_rule == "ball" ? v3::GRAB_RULE_BALL : v3::GRAB_RULE_ORGAN);
    } else if (a->drag.size() == 3) {
      set(e->mutable_drag()->mutable_offset_mm(), a->drag);
    } else if (a->pull.size() == 3) {
      set(e->mutable_pull()->mutable_force_n(), a->pull);
    } else if (a->pin.size() == 3) {
      set(e->mutable_pin()->mutable_point_mm(), a->pin);
      e->mutable_pin()->set_radius_mm(a->radius_mm);
    } else if (a->release) {
      e->mutable_release()->set_keep(a->keep);
    } else if (a->reset) {
      e->mutable_reset();
    }
    v3::ManipulateResponse response;
    RETURN_IF_ERROR(FromGrpc(s.stub().Manipulate(s.Context().get(), request, &response)));
    std::printf("applied; max displacement %.2f mm, lag %.2f mm, inverted tets %lld\n",
                response.max_displacement_mm(), response.lag_mm(),
                static_cast<long long>(response.inverted_tets()));
    if (!response.message().empty()) std::printf("%s\n", response.message().c_str());
    return absl::OkStatus();
  }));
}

// set-camera (SetCamera).
void AddSetCameraCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                         std::shared_ptr<SessionArgs> a) {
  CLI::App* camera = app.add_subcommand("set-camera", "server: SetCamera");
  camera->add_option("--session", a->session_id)->required();
  camera->add_option("POSE", a->camera, "AZ EL [DIST]")->expected(2, 3)->required();
  camera->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::SetCameraRequest request;
    request.set_session_id(a->session_id);
    request.mutable_camera()->set_azimuth_deg(a->camera[0]);
    request.mutable_camera()->set_elevation_deg(a->camera[1]);
    if (a->camera.size() == 3) request.mutable_camera()->set_distance_mm(a->camera[2]);
    v3::SetCameraResponse response;
    return FromGrpc(s.stub().SetCamera(s.Context().get(), request, &response));
  }));
}

// watch: a session's frames (Watch), optionally saved.
void AddWatchCommand(CLI::App& app, const ServerFlags* flags, int* exit_code,
                     std::shared_ptr<SessionArgs> a) {
  CLI::App* watch = app.add_subcommand("watch", "server: Watch a session's frames");
  watch->add_option("--session", a->session_id)->required();
  watch->add_option("--frames", a->frames, "stop after this many frames")->capture_default_str();
  watch->add_option("--out-dir", a->out_dir, "save the frames here");
  watch->add_option("--size", a->size, "W H")->expected(2);
  watch->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v3::WatchRequest request;
    request.set_session_id(a->session_id);
    request.mutable_settings()->set_width(a->size[0]);
    request.mutable_settings()->set_height(a->size[1]);
    auto context = s.Context(true);
    auto reader = s.stub().Watch(context.get(), request);
    if (!a->out_dir.empty()) RETURN_IF_ERROR(MakeDirectories(a->out_dir));
    v3::Frame frame;
    int n = 0;
    while (n < a->frames && reader->Read(&frame)) {
      std::printf("frame %llu: seq %llu %s %zu bytes, render %.1f ms\n",
                  (unsigned long long)frame.frame_number(), (unsigned long long)frame.last_sequence(),
                  frame.interactive() ? "interactive" : "still", frame.image().size(),
                  frame.timings().render_ms());
      if (!a->out_dir.empty()) {
        RETURN_IF_ERROR(WriteFile(fs::path(a->out_dir) / StrCat("watch_", n, ".jpg"), frame.image()));
      }
      ++n;
    }
    // Cancelled by us only once the frames asked for came; a stream the
    // server ended early (PERMISSION_DENIED, NOT_FOUND, ...) keeps its status.
    const bool got_all = n == a->frames;
    if (got_all) context->TryCancel();
    grpc::Status status = reader->Finish();
    return got_all && status.error_code() == grpc::CANCELLED ? absl::OkStatus() : FromGrpc(status);
  }));
}

}  // namespace

void AddSessionCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  auto a = std::make_shared<SessionArgs>();
  AddSessionGetShare(AddSessionOpenListClose(app, flags, exit_code, a), flags, exit_code, a);
  AddSnapshotCommand(app, flags, exit_code, a);
  AddManipulateCommand(app, flags, exit_code, a);
  AddSetCameraCommand(app, flags, exit_code, a);
  AddWatchCommand(app, flags, exit_code, a);
}

}  // namespace vpm::cli

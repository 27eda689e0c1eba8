#include "client/cli/server_commands.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <nlohmann/json.hpp>

#include "client/cli/command_status.h"
#include "client/cli/script_player.h"
#include "server/common/sha256.h"

namespace vpm::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json VolumeJson(const v1::VolumeInfo& v) {
  json j{{"volume_id", v.volume_id()}, {"source", v.source()}, {"bytes", v.bytes()},
         {"sessions", v.sessions()}, {"min_value", v.min_value()}, {"max_value", v.max_value()}};
  j["dims"] = std::vector<int64_t>(v.dims().begin(), v.dims().end());
  j["spacing_mm"] = {v.spacing_mm().x(), v.spacing_mm().y(), v.spacing_mm().z()};
  for (const auto& l : v.landmarks()) {
    j["landmarks"].push_back({{"name", l.name()},
                              {"position_mm", {l.position_mm().x(), l.position_mm().y(),
                                               l.position_mm().z()}}});
  }
  return j;
}

json MeshJson(const v1::MeshInfo& m) {
  const auto& s = m.stats();
  return {{"mesh_id", m.mesh_id()}, {"volume_id", m.volume_id()},
          {"vertices", s.vertices()}, {"tets", s.tets()}, {"hard", s.hard()},
          {"refined", s.refined()}, {"h_mm", s.h_mm()}, {"min_dihedral_deg", s.min_dihedral_deg()}};
}

json SessionJson(const v1::SessionInfo& s) {
  return {{"session_id", s.session_id()}, {"volume_id", s.volume_id()},
          {"mesh_id", s.mesh_id()}, {"viewers", s.viewers()}, {"idle_s", s.idle_s()}};
}

void Print(const json& j) { std::cout << j.dump(2) << "\n"; }

Status WriteBytes(const fs::path& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary);
  file.write(bytes.data(), std::streamsize(bytes.size()));
  if (!file) return absl::PermissionDeniedError(StrCat("cannot write ", path.string()));
  return absl::OkStatus();
}

// Runs `fn` with a connection; the command's exit code from its status.
template <typename Fn>
std::function<void()> WithServer(const ServerFlags* flags, int* exit_code, Fn fn) {
  return [flags, exit_code, fn] {
    auto server = ServerConnection::Connect(*flags);
    *exit_code = ExitWith(server.ok() ? fn(*server) : server.status());
  };
}

Status Upload(const ServerConnection& server, const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return absl::NotFoundError(StrCat(path, ": cannot read"));
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)),
                             std::istreambuf_iterator<char>());
  auto context = server.Context();
  v1::VolumeInfo info;
  auto writer = server.stub().UploadVolume(context.get(), &info);
  v1::UploadVolumeRequest header;
  header.mutable_header()->set_file_name(fs::path(path).filename().string());
  header.mutable_header()->set_total_bytes(int64_t(bytes.size()));
  header.mutable_header()->set_sha256_hex(service::Sha256::HexOf(bytes));
  bool ok = writer->Write(header);
  constexpr size_t kChunk = 1 << 20;
  for (size_t at = 0; ok && at < bytes.size(); at += kChunk) {
    v1::UploadVolumeRequest chunk;
    chunk.set_chunk(bytes.data() + at, std::min(kChunk, bytes.size() - at));
    ok = writer->Write(chunk);
  }
  writer->WritesDone();
  RETURN_IF_ERROR(FromGrpc(writer->Finish()));
  Print(VolumeJson(info));
  return absl::OkStatus();
}

void AddVolumeServerCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  CLI::App* volume = app.get_subcommand("volume");
  auto source = std::make_shared<std::string>();
  CLI::App* load = volume->add_subcommand("load", "server: LoadVolume (data-root path or phantom:)");
  load->add_option("SOURCE", *source, "path under the server's data root, or phantom:NAME")->required();
  load->callback(WithServer(flags, exit_code, [source](const ServerConnection& s) -> Status {
    v1::LoadVolumeRequest request;
    request.set_source(*source);
    v1::VolumeInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().LoadVolume(s.Context().get(), request, &info)));
    Print(VolumeJson(info));
    return absl::OkStatus();
  }));
  auto file = std::make_shared<std::string>();
  CLI::App* upload = volume->add_subcommand("upload", "server: UploadVolume in 1 MiB chunks with SHA-256");
  upload->add_option("FILE", *file, ".nii, .nii.gz, .nrrd or .mha")->required();
  upload->callback(WithServer(flags, exit_code, [file](const ServerConnection& s) {
    return Upload(s, *file);
  }));
  volume->add_subcommand("list", "server: ListVolumes")
      ->callback(WithServer(flags, exit_code, [](const ServerConnection& s) -> Status {
        v1::ListVolumesResponse response;
        RETURN_IF_ERROR(FromGrpc(s.stub().ListVolumes(s.Context().get(), {}, &response)));
        json j = json::array();
        for (const auto& v : response.volumes()) j.push_back(VolumeJson(v));
        Print(j);
        return absl::OkStatus();
      }));
  auto id = std::make_shared<std::string>();
  CLI::App* get = volume->add_subcommand("get", "server: GetVolume");
  get->add_option("ID", *id)->required();
  get->callback(WithServer(flags, exit_code, [id](const ServerConnection& s) -> Status {
    v1::GetVolumeRequest request;
    request.set_volume_id(*id);
    v1::VolumeInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetVolume(s.Context().get(), request, &info)));
    Print(VolumeJson(info));
    return absl::OkStatus();
  }));
  CLI::App* del = volume->add_subcommand("delete", "server: DeleteVolume");
  del->add_option("ID", *id)->required();
  del->callback(WithServer(flags, exit_code, [id](const ServerConnection& s) -> Status {
    v1::DeleteVolumeRequest request;
    request.set_volume_id(*id);
    v1::DeleteVolumeResponse response;
    return FromGrpc(s.stub().DeleteVolume(s.Context().get(), request, &response));
  }));
}

void AddMeshServerCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  struct Args {
    std::string volume_id, mesh_id, json_out;
    std::vector<int64_t> grid;
    int64_t target = 0;
    std::string tf;
    std::vector<double> point;
    bool geometry = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* build = app.add_subcommand("mesh-build", "server: BuildMesh");
  build->add_option("--volume-id", a->volume_id)->required();
  build->add_option("--grid", a->grid, "GX GY GZ")->expected(3);
  build->add_option("--target", a->target, "kept vertices (0: 250)");
  build->add_option("--tf", a->tf, "transfer-function preset or v:c,...");
  build->add_option("--refine-at", a->point, "X Y Z mm")->expected(3);
  build->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::BuildMeshRequest request;
    request.set_volume_id(a->volume_id);
    for (int64_t g : a->grid) request.mutable_params()->add_grid(g);
    request.mutable_params()->set_target(a->target);
    request.mutable_params()->set_tf(a->tf);
    if (a->point.size() == 3) {
      request.mutable_params()->set_has_refine_at(true);
      auto* p = request.mutable_params()->mutable_refine_at_mm();
      p->set_x(a->point[0]);
      p->set_y(a->point[1]);
      p->set_z(a->point[2]);
    }
    v1::MeshInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().BuildMesh(s.Context().get(), request, &info)));
    Print(MeshJson(info));
    return absl::OkStatus();
  }));
  CLI::App* get = app.add_subcommand("mesh-get", "server: GetMesh");
  get->add_option("ID", a->mesh_id)->required();
  get->add_flag("--geometry", a->geometry, "include vertices and tets");
  get->add_option("--json", a->json_out, "write the response as JSON here");
  get->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::GetMeshRequest request;
    request.set_mesh_id(a->mesh_id);
    request.set_include_geometry(a->geometry || !a->json_out.empty());
    v1::GetMeshResponse response;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetMesh(s.Context().get(), request, &response)));
    json j = MeshJson(response.info());
    if (!a->json_out.empty()) {
      for (const auto& v : response.vertices()) {
        j["vertices"].push_back({{"position_mm", {v.position_mm().x(), v.position_mm().y(),
                                                  v.position_mm().z()}},
                                 {"kind", v.kind()}, {"hard", v.hard()}});
      }
      for (const auto& t : response.tets()) j["tets"].push_back({t.a(), t.b(), t.c(), t.d()});
      std::ofstream(a->json_out) << j.dump() << "\n";
      std::printf("wrote %s\n", a->json_out.c_str());
    } else {
      Print(j);
    }
    return absl::OkStatus();
  }));
  CLI::App* refine = app.add_subcommand("mesh-refine", "server: RefineMesh (a new mesh)");
  refine->add_option("ID", a->mesh_id)->required();
  refine->add_option("POINT", a->point, "X Y Z mm")->expected(3)->required();
  refine->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::RefineMeshRequest request;
    request.set_mesh_id(a->mesh_id);
    request.mutable_point_mm()->set_x(a->point[0]);
    request.mutable_point_mm()->set_y(a->point[1]);
    request.mutable_point_mm()->set_z(a->point[2]);
    v1::MeshInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().RefineMesh(s.Context().get(), request, &info)));
    Print(MeshJson(info));
    return absl::OkStatus();
  }));
}

void AddSessionCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  struct Args {
    std::string volume_id, mesh_id, session_id, out, out_dir;
    std::vector<double> camera, grab, drag, pull;
    std::vector<int> size{512, 512};
    bool release = false;
    int frames = 10;
  };
  auto a = std::make_shared<Args>();
  CLI::App* session = app.add_subcommand("session", "server: sessions");
  session->require_subcommand(1);
  CLI::App* open = session->add_subcommand("open", "OpenSession");
  open->add_option("--volume-id", a->volume_id);
  open->add_option("--mesh-id", a->mesh_id, "empty: a mesh with default parameters");
  open->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::OpenSessionRequest request;
    request.set_volume_id(a->volume_id);
    request.set_mesh_id(a->mesh_id);
    v1::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenSession(s.Context().get(), request, &info)));
    Print(SessionJson(info));
    return absl::OkStatus();
  }));
  session->add_subcommand("list", "ListSessions")
      ->callback(WithServer(flags, exit_code, [](const ServerConnection& s) -> Status {
        v1::ListSessionsResponse response;
        RETURN_IF_ERROR(FromGrpc(s.stub().ListSessions(s.Context().get(), {}, &response)));
        json j = json::array();
        for (const auto& x : response.sessions()) j.push_back(SessionJson(x));
        Print(j);
        return absl::OkStatus();
      }));
  CLI::App* close = session->add_subcommand("close", "CloseSession");
  close->add_option("ID", a->session_id)->required();
  close->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::CloseSessionRequest request;
    request.set_session_id(a->session_id);
    v1::CloseSessionResponse response;
    return FromGrpc(s.stub().CloseSession(s.Context().get(), request, &response));
  }));

  CLI::App* snapshot = app.add_subcommand("snapshot", "server: Render one still frame");
  snapshot->add_option("--session", a->session_id)->required();
  snapshot->add_option("--camera", a->camera, "AZ EL DIST (DIST 0: fit)")->expected(3);
  snapshot->add_option("--size", a->size, "W H")->expected(2);
  snapshot->add_option("--out", a->out, "frame.jpg or frame.png")->required();
  snapshot->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::RenderRequest request;
    request.set_session_id(a->session_id);
    if (a->camera.size() == 3) {
      request.mutable_camera()->set_azimuth_deg(a->camera[0]);
      request.mutable_camera()->set_elevation_deg(a->camera[1]);
      request.mutable_camera()->set_distance_mm(a->camera[2]);
    }
    request.mutable_settings()->set_width(a->size[0]);
    request.mutable_settings()->set_height(a->size[1]);
    request.mutable_settings()->set_encoding(a->out.ends_with(".png") ? "png" : "jpeg");
    v1::Frame frame;
    RETURN_IF_ERROR(FromGrpc(s.stub().Render(s.Context().get(), request, &frame)));
    RETURN_IF_ERROR(WriteBytes(a->out, frame.image()));
    std::printf("wrote %s (%dx%d, %zu bytes; render %.1f ms, encode %.1f ms)\n", a->out.c_str(),
                frame.width(), frame.height(), frame.image().size(), frame.timings().render_ms(),
                frame.timings().encode_ms());
    return absl::OkStatus();
  }));

  CLI::App* manipulate = app.add_subcommand("manipulate", "server: Manipulate (one event)");
  manipulate->add_option("--session", a->session_id)->required();
  manipulate->add_option("--grab", a->grab, "X Y Z mm")->expected(3);
  manipulate->add_option("--drag", a->drag, "DX DY DZ mm")->expected(3);
  manipulate->add_option("--pull", a->pull, "FX FY FZ N")->expected(3);
  manipulate->add_flag("--release", a->release);
  manipulate->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::ManipulateRequest request;
    request.set_session_id(a->session_id);
    v1::ClientEvent* e = request.mutable_event();
    e->set_sequence(1);
    auto set = [](v1::Vec3* v, const std::vector<double>& x) {
      v->set_x(x[0]);
      v->set_y(x[1]);
      v->set_z(x[2]);
    };
    if (a->grab.size() == 3) set(e->mutable_grab()->mutable_point_mm(), a->grab);
    else if (a->drag.size() == 3) set(e->mutable_drag()->mutable_offset_mm(), a->drag);
    else if (a->pull.size() == 3) set(e->mutable_pull()->mutable_force_n(), a->pull);
    else if (a->release) e->mutable_release();
    v1::ManipulateResponse response;
    RETURN_IF_ERROR(FromGrpc(s.stub().Manipulate(s.Context().get(), request, &response)));
    std::printf("applied; max displacement %.2f mm\n", response.max_displacement_mm());
    return absl::OkStatus();
  }));

  CLI::App* camera = app.add_subcommand("set-camera", "server: SetCamera");
  camera->add_option("--session", a->session_id)->required();
  camera->add_option("POSE", a->camera, "AZ EL [DIST]")->expected(2, 3)->required();
  camera->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::SetCameraRequest request;
    request.set_session_id(a->session_id);
    request.mutable_camera()->set_azimuth_deg(a->camera[0]);
    request.mutable_camera()->set_elevation_deg(a->camera[1]);
    if (a->camera.size() == 3) request.mutable_camera()->set_distance_mm(a->camera[2]);
    v1::SetCameraResponse response;
    return FromGrpc(s.stub().SetCamera(s.Context().get(), request, &response));
  }));

  CLI::App* watch = app.add_subcommand("watch", "server: Watch a session's frames");
  watch->add_option("--session", a->session_id)->required();
  watch->add_option("--frames", a->frames, "stop after this many frames")->capture_default_str();
  watch->add_option("--out-dir", a->out_dir, "save the frames here");
  watch->add_option("--size", a->size, "W H")->expected(2);
  watch->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) -> Status {
    v1::WatchRequest request;
    request.set_session_id(a->session_id);
    request.mutable_settings()->set_width(a->size[0]);
    request.mutable_settings()->set_height(a->size[1]);
    auto context = s.Context(true);
    auto reader = s.stub().Watch(context.get(), request);
    if (!a->out_dir.empty()) fs::create_directories(a->out_dir);
    v1::Frame frame;
    int n = 0;
    while (n < a->frames && reader->Read(&frame)) {
      std::printf("frame %llu: seq %llu %s %zu bytes, render %.1f ms\n",
                  (unsigned long long)frame.frame_number(), (unsigned long long)frame.last_sequence(),
                  frame.interactive() ? "interactive" : "still", frame.image().size(),
                  frame.timings().render_ms());
      if (!a->out_dir.empty()) {
        RETURN_IF_ERROR(WriteBytes(fs::path(a->out_dir) / StrCat("watch_", n, ".jpg"), frame.image()));
      }
      ++n;
    }
    context->TryCancel();
    grpc::Status status = reader->Finish();
    return status.error_code() == grpc::CANCELLED ? absl::OkStatus() : FromGrpc(status);
  }));
}

Status Play(const ServerConnection& s, const std::string& script_path, std::string session_id,
            const std::string& out_dir, std::string report_path) {
  ASSIGN_OR_RETURN(json script_json, ReadJsonFile(script_path));
  const std::string source = script_json.value("volume", "phantom:abdomen?size=64");
  v1::VolumeInfo volume;
  const bool opened_here = session_id.empty();
  if (opened_here) {
    v1::LoadVolumeRequest load;
    load.set_source(source);
    RETURN_IF_ERROR(FromGrpc(s.stub().LoadVolume(s.Context().get(), load, &volume)));
    v1::OpenSessionRequest open;
    open.set_volume_id(volume.volume_id());
    v1::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenSession(s.Context().get(), open, &info)));
    session_id = info.session_id();
    std::printf("volume %s, session %s\n", volume.volume_id().c_str(), session_id.c_str());
  } else {
    v1::ListSessionsResponse sessions;
    RETURN_IF_ERROR(FromGrpc(s.stub().ListSessions(s.Context().get(), {}, &sessions)));
    for (const auto& x : sessions.sessions()) {
      if (x.session_id() == session_id) {
        v1::GetVolumeRequest get;
        get.set_volume_id(x.volume_id());
        RETURN_IF_ERROR(FromGrpc(s.stub().GetVolume(s.Context().get(), get, &volume)));
      }
    }
    if (volume.volume_id().empty()) return absl::NotFoundError(StrCat("session ", session_id));
  }
  ASSIGN_OR_RETURN(Script script, ParseScript(script_json, volume));
  if (!out_dir.empty()) fs::create_directories(out_dir);
  PlayOptions options;
  options.session_id = session_id;
  options.on_frame = [&](const v1::Frame& frame, int64_t index) {
    if (out_dir.empty()) return;
    char name[64];
    std::snprintf(name, sizeof name, "frame_%04lld.%s", (long long)index,
                  frame.encoding() == "png" ? "png" : "jpg");
    (void)WriteBytes(fs::path(out_dir) / name, frame.image());
  };
  PlayResult result = PlayScript(s, script, options);
  if (opened_here) {
    // The session this command opened goes with it, whatever the outcome.
    v1::CloseSessionRequest close;
    close.set_session_id(session_id);
    v1::CloseSessionResponse closed;
    (void)s.stub().CloseSession(s.Context().get(), close, &closed);
  }
  RETURN_IF_ERROR(result.status);
  std::vector<double> latency, render, fem, warp, encode, intervals;
  int64_t bytes = 0, interactive = 0;
  for (size_t i = 0; i < result.frames.size(); ++i) {
    const FrameRecord& f = result.frames[i];
    if (f.latency_ms >= 0) latency.push_back(f.latency_ms);
    render.push_back(f.timings.render_ms());
    fem.push_back(f.timings.fem_ms());
    warp.push_back(f.timings.warp_ms());
    encode.push_back(f.timings.encode_ms());
    if (i > 0) intervals.push_back(f.received_ms - result.frames[i - 1].received_ms);
    bytes += f.bytes;
    interactive += f.interactive;
  }
  const double seconds = result.duration_ms / 1000.0;
  json report{{"session_id", session_id},
              {"events", result.events_sent},
              {"frames", result.frames.size()},
              {"interactive_frames", interactive},
              {"duration_s", seconds},
              {"fps", seconds > 0 ? double(result.frames.size()) / seconds : 0.0},
              {"time_to_first_frame_ms", result.first_frame_ms},
              {"bytes_per_frame", result.frames.empty() ? 0 : bytes / int64_t(result.frames.size())},
              {"superseded", result.frames.empty() ? 0 : result.frames.back().superseded},
              {"latency_ms", Summarize(latency)},
              {"frame_interval_ms", Summarize(intervals)},
              {"server_render_ms", Summarize(render)},
              {"server_fem_ms", Summarize(fem)},
              {"server_warp_ms", Summarize(warp)},
              {"server_encode_ms", Summarize(encode)}};
  if (report_path.empty() && !out_dir.empty()) report_path = (fs::path(out_dir) / "report.json").string();
  if (!report_path.empty()) std::ofstream(report_path) << report.dump(2) << "\n";
  std::printf("%zu frames (%lld interactive) for %lld events in %.2f s: %.1f fps, first frame %.0f ms\n",
              result.frames.size(), (long long)interactive, (long long)result.events_sent, seconds,
              report["fps"].get<double>(), result.first_frame_ms);
  std::printf("%-18s %8s %8s %8s %8s\n", "ms", "avg", "p50", "p95", "max");
  for (auto [name, key] : {std::pair{"event->frame", "latency_ms"},
                           std::pair{"server render", "server_render_ms"},
                           std::pair{"server fem", "server_fem_ms"},
                           std::pair{"server warp", "server_warp_ms"},
                           std::pair{"server encode", "server_encode_ms"}}) {
    const json& j = report[key];
    if (j["count"].get<size_t>() == 0) continue;
    std::printf("%-18s %8.1f %8.1f %8.1f %8.1f\n", name, j["average"].get<double>(),
                j["p50"].get<double>(), j["p95"].get<double>(), j["slowest"].get<double>());
  }
  if (!out_dir.empty()) std::printf("frames in %s\n", out_dir.c_str());
  if (!report_path.empty()) std::printf("report in %s\n", report_path.c_str());
  return absl::OkStatus();
}

}  // namespace

void AddServerFlags(CLI::App& app, ServerFlags* flags) {
  app.add_option("--server", flags->address, "HOST:PORT of a vpm-server (server commands)");
  app.add_option("--token", flags->token, "bearer token (default: env VPM_TOKEN)");
  app.add_option("--tls-ca", flags->tls_ca, "CA certificate (PEM) of a TLS server: turns TLS on");
  app.add_option("--tls-cert", flags->tls_cert, "client certificate (PEM) for mutual TLS");
  app.add_option("--tls-key", flags->tls_key, "client private key (PEM) for mutual TLS");
  app.add_option("--deadline-s", flags->deadline_s, "deadline of unary calls, seconds")
      ->capture_default_str();
}

void AddServerCommands(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  AddVolumeServerCommands(app, flags, exit_code);
  AddMeshServerCommands(app, flags, exit_code);
  AddSessionCommands(app, flags, exit_code);
  struct PlayArgs {
    std::string script, session, out_dir, report;
  };
  auto a = std::make_shared<PlayArgs>();
  CLI::App* play = app.add_subcommand("play", "server: replay an interaction script over Interact");
  play->add_option("SCRIPT", a->script, "script JSON (see client/cli/script_player.h)")->required();
  play->add_option("--session", a->session,
                   "play on this session (default: open one on the script's volume, closed at the end)");
  play->add_option("--out-dir", a->out_dir, "save frames and report.json here");
  play->add_option("--report", a->report, "timing report JSON");
  play->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) {
    return Play(s, a->script, a->session, a->out_dir, a->report);
  }));
}

}  // namespace vpm::cli

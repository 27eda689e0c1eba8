// vpm-load: N concurrent sessions (or N clients on one session) each playing
// an interaction script over Interact for a duration, optionally swept over
// concurrency levels; a ghz-style report on stdout and in JSON.
#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "client/common/command_status.h"
#include "client/common/script_player.h"
#include "server/common/write_file.h"

namespace vpm::load {
namespace {

using nlohmann::json;
using cli::FromGrpc;

struct LoadArgs {
  cli::ServerFlags server;
  int sessions = 1;
  double duration_s = 10;
  std::string script;
  std::string sweep;
  std::string json_out;
  bool shared_session = false;
};

json Histogram(const std::vector<double>& v, int buckets = 10) {
  json out = json::array();
  if (v.empty()) return out;
  const auto [lo_it, hi_it] = std::minmax_element(v.begin(), v.end());
  const double lo = *lo_it, hi = *hi_it, width = (hi - lo) / buckets;
  std::vector<int64_t> counts(buckets, 0);
  for (double x : v) {
    int b = width > 0 ? int((x - lo) / width) : 0;
    counts[std::min(b, buckets - 1)]++;
  }
  for (int b = 0; b < buckets; ++b) {
    out.push_back({{"mark_ms", lo + width * (b + 1)}, {"count", counts[b]}});
  }
  return out;
}

// Opens `count` sessions on the mesh; the status codes of those refused
// are counted in `codes`.
std::vector<std::string> OpenSessions(const cli::ServerConnection& s, const std::string& mesh_id,
                                      int count, std::map<std::string, int64_t>& codes) {
  std::vector<std::string> sessions;
  for (int i = 0; i < count; ++i) {
    v3::OpenSessionRequest open;
    open.set_mesh_id(mesh_id);
    v3::SessionInfo info;
    grpc::Status status = s.stub().OpenSession(s.Context().get(), open, &info);
    if (!status.ok()) {
      codes[absl::StatusCodeToString(FromGrpc(status).code())]++;
      continue;
    }
    sessions.push_back(info.session_id());
  }
  return sessions;
}

// `concurrency` clients playing the script at once, client i in session i
// modulo the sessions open.
std::vector<cli::PlayResult> PlayConcurrently(const cli::ServerConnection& s,
                                              const cli::Script& script,
                                              const std::vector<std::string>& sessions,
                                              int concurrency, double duration_s) {
  std::vector<cli::PlayResult> results(concurrency);
  std::vector<std::thread> threads;
  for (int i = 0; i < concurrency; ++i) {
    threads.emplace_back([&, i] {
      cli::PlayOptions options;
      options.session_id = sessions[i % sessions.size()];
      options.duration_s = duration_s;
      results[i] = cli::PlayScript(s, script, options);
    });
  }
  for (auto& t : threads) t.join();
  return results;
}

// One level's figures over its clients' plays.
json LevelReport(const std::vector<cli::PlayResult>& results, int concurrency, size_t sessions,
                 std::map<std::string, int64_t> codes) {
  std::vector<double> latency, frame_latency, still_latency, first, fps, jitter;
  int64_t frames = 0, bytes = 0, superseded = 0;
  double duration = 0;
  for (const cli::PlayResult& r : results) {
    codes[absl::StatusCodeToString(r.status.code())]++;
    std::vector<double> intervals;
    for (size_t i = 0; i < r.frames.size(); ++i) {
      if (r.frames[i].latency_ms >= 0) {
        frame_latency.push_back(r.frames[i].latency_ms);
        // The full-quality frame, from the event it shows: still delay,
        // rungs, the still's cast.
        if (!r.frames[i].interactive) still_latency.push_back(r.frames[i].latency_ms);
      }
      bytes += r.frames[i].bytes;
      if (i > 0) intervals.push_back(r.frames[i].received_ms - r.frames[i - 1].received_ms);
    }
    latency.insert(latency.end(), r.event_latency_ms.begin(), r.event_latency_ms.end());
    frames += int64_t(r.frames.size());
    if (!r.frames.empty()) superseded += int64_t(r.frames.back().superseded);
    if (r.first_frame_ms >= 0) first.push_back(r.first_frame_ms);
    if (r.duration_ms > 0) fps.push_back(double(r.frames.size()) / (r.duration_ms / 1000.0));
    const json j = cli::Summarize(intervals);
    if (j.contains("stddev")) jitter.push_back(j["stddev"].get<double>());
    duration = std::max(duration, r.duration_ms / 1000.0);
  }
  return json{{"concurrency", concurrency},
              {"sessions", sessions},
              {"count", frames},
              {"duration_s", duration},
              {"rate_fps", duration > 0 ? double(frames) / duration : 0.0},
              {"latency_ms", cli::Summarize(latency)},
              {"frame_latency_ms", cli::Summarize(frame_latency)},
              {"still_latency_ms", cli::Summarize(still_latency)},
              {"histogram", Histogram(latency)},
              {"status_codes", codes},
              {"time_to_first_frame_ms", cli::Summarize(first)},
              {"fps_per_session", cli::Summarize(fps)},
              {"jitter_ms", cli::Summarize(jitter)},
              {"superseded", superseded},
              {"bytes_per_frame", frames > 0 ? bytes / frames : 0}};
}

Result<json> RunLevel(const cli::ServerConnection& s, const json& script_json, int concurrency,
                      const LoadArgs& args) {
  v3::LoadVolumeRequest load;
  load.set_source(script_json.value("volume", "phantom:abdomen?size=64"));
  v3::VolumeInfo volume;
  RETURN_IF_ERROR(FromGrpc(s.stub().LoadVolume(s.Context().get(), load, &volume)));
  ASSIGN_OR_RETURN(cli::Script script, cli::ParseScript(script_json, volume));
  v3::BuildMeshRequest build;
  build.set_volume_id(volume.volume_id());
  v3::MeshInfo mesh;
  RETURN_IF_ERROR(FromGrpc(s.stub().BuildMesh(s.Context().get(), build, &mesh)));
  std::map<std::string, int64_t> codes;
  const std::vector<std::string> sessions =
      OpenSessions(s, mesh.mesh_id(), args.shared_session ? 1 : concurrency, codes);
  if (sessions.empty()) return absl::ResourceExhaustedError("no session could be opened");
  const std::vector<cli::PlayResult> results =
      PlayConcurrently(s, script, sessions, concurrency, args.duration_s);
  for (const std::string& id : sessions) s.CloseSessionQuietly(id);
  v3::DeleteVolumeRequest del;
  del.set_volume_id(volume.volume_id());
  v3::DeleteVolumeResponse deleted;
  (void)s.stub().DeleteVolume(s.Context().get(), del, &deleted);
  return LevelReport(results, concurrency, sessions.size(), std::move(codes));
}

void PrintLevel(const json& l) {
  const json& lat = l["latency_ms"];
  std::printf("\nConcurrency %d (%zu sessions), %.1f s\n", l["concurrency"].get<int>(),
              l["sessions"].get<size_t>(), l["duration_s"].get<double>());
  std::printf("  Count:        %lld frames\n", (long long)l["count"].get<int64_t>());
  std::printf("  Rate:         %.1f frames/s (aggregate)\n", l["rate_fps"].get<double>());
  if (lat["count"].get<size_t>() > 0) {
    std::printf("  Fastest:      %.1f ms\n  Slowest:      %.1f ms\n  Average:      %.1f ms\n",
                lat["fastest"].get<double>(), lat["slowest"].get<double>(),
                lat["average"].get<double>());
    std::printf("  Latency distribution (event to the first frame showing it, %zu events):\n",
                lat["count"].get<size_t>());
    for (const char* p : {"p50", "p90", "p95", "p99"}) {
      std::printf("    %s: %.1f ms\n", p, lat[p].get<double>());
    }
    const json& per_frame = l["frame_latency_ms"];
    if (per_frame["count"].get<size_t>() > 0) {
      std::printf("  Per frame, stills that show an event again included: p50 %.1f ms, p99 %.1f "
                  "ms\n",
                  per_frame["p50"].get<double>(), per_frame["p99"].get<double>());
    }
    const json& stills = l["still_latency_ms"];
    if (stills["count"].get<size_t>() > 0) {
      std::printf(
          "  Stills, from the event each shows (still delay included): p50 %.1f ms, p99 "
          "%.1f ms, %zu stills\n",
          stills["p50"].get<double>(), stills["p99"].get<double>(), stills["count"].get<size_t>());
    }
    std::printf("  Histogram:\n");
    int64_t max_count = 1;
    for (const auto& b : l["histogram"]) max_count = std::max(max_count, b["count"].get<int64_t>());
    for (const auto& b : l["histogram"]) {
      const int64_t c = b["count"].get<int64_t>();
      std::printf("    %9.1f [%6lld] |%s\n", b["mark_ms"].get<double>(), (long long)c,
                  std::string(size_t(40 * c / max_count), '*').c_str());
    }
  }
  const json& ttff = l["time_to_first_frame_ms"];
  if (ttff["count"].get<size_t>() > 0) {
    std::printf("  Time to first frame: avg %.1f ms, max %.1f ms\n", ttff["average"].get<double>(),
                ttff["slowest"].get<double>());
  }
  const json& fps = l["fps_per_session"];
  if (fps["count"].get<size_t>() > 0) {
    std::printf("  FPS per session: avg %.1f, min %.1f\n", fps["average"].get<double>(),
                fps["fastest"].get<double>());
  }
  const json& jit = l["jitter_ms"];
  if (jit["count"].get<size_t>() > 0) {
    std::printf("  Frame-interval jitter (stddev): avg %.1f ms\n", jit["average"].get<double>());
  }
  std::printf("  Superseded frames: %lld\n  Bytes per frame: %lld\n",
              (long long)l["superseded"].get<int64_t>(), (long long)l["bytes_per_frame"].get<int64_t>());
  std::printf("  Status code distribution:\n");
  for (const auto& [code, n] : l["status_codes"].items()) {
    std::printf("    [%s] %lld responses\n", code.c_str(), (long long)n.get<int64_t>());
  }
}

Status Run(const LoadArgs& args) {
  ASSIGN_OR_RETURN(cli::ServerConnection server, cli::ServerConnection::Connect(args.server));
  json script = cli::DefaultScriptJson();
  if (!args.script.empty()) {
    ASSIGN_OR_RETURN(script, cli::ReadJsonFile(args.script));
  }
  std::vector<int> levels;
  if (args.sweep.empty()) {
    levels.push_back(args.sessions);
  } else {
    std::stringstream in(args.sweep);
    std::string item;
    while (std::getline(in, item, ',')) {
      try {
        levels.push_back(std::stoi(item));
      } catch (...) {
        return absl::InvalidArgumentError(StrCat("--sweep: '", item, "' is not a number"));
      }
    }
  }
  json report{{"server", args.server.address}, {"duration_s", args.duration_s},
              {"shared_session", args.shared_session}, {"levels", json::array()}};
  for (int level : levels) {
    if (level < 1) return absl::InvalidArgumentError("--sessions/--sweep: at least 1");
    ASSIGN_OR_RETURN(json result, RunLevel(server, script, level, args));
    PrintLevel(result);
    report["levels"].push_back(result);
  }
  if (levels.size() > 1) {
    std::printf("\n%6s %10s %10s %10s %10s %8s\n", "conc", "fps", "p50 ms", "p99 ms", "errors",
                "fps/ses");
    for (const json& l : report["levels"]) {
      int64_t errors = 0;
      for (const auto& [code, n] : l["status_codes"].items()) {
        if (code != "OK") errors += n.get<int64_t>();
      }
      const json& lat = l["latency_ms"];
      std::printf("%6d %10.1f %10.1f %10.1f %10lld %8.1f\n", l["concurrency"].get<int>(),
                  l["rate_fps"].get<double>(), lat.value("p50", 0.0), lat.value("p99", 0.0),
                  (long long)errors, l["fps_per_session"].value("average", 0.0));
    }
  }
  if (!args.json_out.empty()) {
    RETURN_IF_ERROR(WriteFile(args.json_out, report.dump(2) + "\n"));
    std::printf("\nreport in %s\n", args.json_out.c_str());
  }
  return absl::OkStatus();
}

}  // namespace
}  // namespace vpm::load

int main(int argc, char** argv) {
  CLI::App app{"vpm-load: concurrent Interact sessions against a vpm-server, ghz-style report"};
  vpm::load::LoadArgs args;
  app.add_option("--server", args.server.address, "HOST:PORT")->required();
  app.add_option("--token", args.server.token, "bearer token (default: env VPM_TOKEN)");
  app.add_option("--tls-ca", args.server.tls_ca, "CA certificate (PEM) of a TLS server");
  app.add_option("--tls-cert", args.server.tls_cert, "client certificate (PEM) for mutual TLS");
  app.add_option("--tls-key", args.server.tls_key, "client private key (PEM) for mutual TLS");
  app.add_option("--session-key", args.server.session_key,
                 "x-vpm-session of every call: behind a balancer all of this run's sessions "
                 "share one replica (default: env VPM_SESSION_KEY, else one key per user and "
                 "host)");
  app.add_option("--sessions", args.sessions, "concurrent clients")->capture_default_str();
  app.add_option("--duration", args.duration_s, "seconds each client plays (looping)")
      ->capture_default_str();
  app.add_option("--script", args.script, "interaction script JSON (default: built in)");
  app.add_option("--sweep", args.sweep, "concurrency levels, e.g. 1,2,4,8,16");
  app.add_option("--json", args.json_out, "write the report as JSON");
  app.add_flag("--shared-session", args.shared_session, "all clients on one session");
  CLI11_PARSE(app, argc, argv);
  return vpm::cli::ExitWith(vpm::load::Run(args));
}

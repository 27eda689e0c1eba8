#include "client/cli/play_command.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "client/common/interrupt.h"
#include "client/common/script_player.h"
#include "client/common/script_resume.h"
#include "proto/enum_names.h"
#include "client/cli/server_flags.h"
#include "server/common/clock.h"
#include "server/common/write_file.h"

namespace vpm::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Sessions reopened after the one in use was lost with its replica.
constexpr int kMaxReopens = 3;
// How long a reopen keeps trying while the balancer has no replica for the
// key (or the one it picks is draining), seconds.
constexpr double kReopenPatienceS = 60;

// Runs `attempt` until it succeeds or fails with other than UNAVAILABLE (the
// balancer has not yet seen the replica go, or a draining replica refuses
// new sessions), backing off from 0.25 s to 2 s, for kReopenPatienceS.
template <typename T>
Result<T> RetryWhileUnavailable(const std::function<Result<T>()>& attempt) {
  const SteadyClock::time_point start = SteadyClock::now();
  double wait_s = 0.25;
  while (true) {
    Result<T> result = attempt();
    if (result.ok() || !absl::IsUnavailable(result.status()) ||
        MsSince(start) / 1000 + wait_s > kReopenPatienceS) {
      return result;
    }
    std::this_thread::sleep_for(std::chrono::duration<double>(wait_s));
    wait_s = std::min(2.0, wait_s * 2);
  }
}

// Loads `source` and opens a session on it, where the balancer sends the
// session key now.
Result<std::string> Reopen(const ServerConnection& s, const std::string& source) {
  return RetryWhileUnavailable<std::string>([&]() -> Result<std::string> {
    v3::LoadVolumeRequest load;
    load.set_source(source);
    v3::VolumeInfo volume;
    RETURN_IF_ERROR(FromGrpc(s.stub().LoadVolume(s.Context().get(), load, &volume)));
    v3::OpenSessionRequest open;
    open.set_volume_id(volume.volume_id());
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenSession(s.Context().get(), open, &info)));
    return info.session_id();
  });
}

// A session on case `case_id` (OpenCase: the server replays what the case
// holds) where the balancer sends the key now, how many manipulations it
// holds, and which (ExportCase: its events in effect, in order; not kept
// when the export is refused, e.g. for a case of an uploaded volume).
// FailedPrecondition when the server keeps no cases.
struct ReopenedCase {
  std::string session_id;
  int64_t events = 0;
  Result<v3::CaseArchive> archive = absl::UnknownError("not exported");
};
Result<ReopenedCase> ReopenCase(const ServerConnection& s, const std::string& case_id) {
  return RetryWhileUnavailable<ReopenedCase>([&]() -> Result<ReopenedCase> {
    v3::OpenCaseRequest open;
    open.set_case_id(case_id);
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenCase(s.Context().get(), open, &info)));
    v3::GetCaseRequest get;
    get.set_case_id(case_id);
    v3::CaseInfo kept;
    RETURN_IF_ERROR(FromGrpc(s.stub().GetCase(s.Context().get(), get, &kept)));
    v3::ExportCaseRequest request;
    request.set_case_id(case_id);
    v3::CaseArchive archive;
    Status exported = FromGrpc(s.stub().ExportCase(s.Context().get(), request, &archive));
    if (absl::IsUnavailable(exported)) return exported;  // tried again
    ReopenedCase reopened{info.session_id(), kept.events()};
    if (exported.ok()) reopened.archive = std::move(archive);
    else reopened.archive = exported;
    return reopened;
  });
}

// Where the script goes on in a reopened case: after the manipulation its
// last event matches (script_resume.h), else, said on stderr, after as
// many manipulations as it holds.
int64_t ResumeIndex(const Script& script, const ReopenedCase& in_case) {
  Status why = in_case.archive.status();
  if (!in_case.archive.ok()) {
    why = Status(why.code(), StrCat("the case's events could not be read (", why.message(), ")"));
  } else {
    const std::vector<v3::CaseArchiveEvent> events(in_case.archive->events().begin(),
                                                   in_case.archive->events().end());
    Result<int64_t> index = IndexAfterCaseEvents(script, events);
    if (index.ok()) return *index;
    why = index.status();
  }
  std::fprintf(stderr, "vpm play: %s; going on after its first %lld manipulations\n",
               std::string(why.message()).c_str(), (long long)in_case.events);
  return IndexAfterManipulations(script, in_case.events);
}

// Appends a segment's frames (times shifted by offset_ms), event latencies
// and counts.
void Append(const PlayResult& segment, double offset_ms, PlayResult* all) {
  for (FrameRecord f : segment.frames) {
    f.received_ms += offset_ms;
    all->frames.push_back(f);
  }
  if (all->first_frame_ms < 0 && segment.first_frame_ms >= 0) {
    all->first_frame_ms = segment.first_frame_ms + offset_ms;
  }
  all->events_sent += segment.events_sent;
  all->event_latency_ms.insert(all->event_latency_ms.end(), segment.event_latency_ms.begin(),
                               segment.event_latency_ms.end());
  all->status = segment.status;
}

// The session a script plays in: one opened here on the script's volume,
// or the one --session names (its volume found through ListSessions).
struct PlayTarget {
  v3::VolumeInfo volume;
  std::string session_id;
  std::string case_id;  // the session's case, when the server keeps cases
  bool opened_here = false;
};

Result<PlayTarget> OpenOrFindSession(const ServerConnection& s, const std::string& source,
                                     const std::string& session_id) {
  PlayTarget t{.session_id = session_id, .opened_here = session_id.empty()};
  if (t.opened_here) {
    v3::LoadVolumeRequest load;
    load.set_source(source);
    RETURN_IF_ERROR(FromGrpc(s.stub().LoadVolume(s.Context().get(), load, &t.volume)));
    v3::OpenSessionRequest open;
    open.set_volume_id(t.volume.volume_id());
    v3::SessionInfo info;
    RETURN_IF_ERROR(FromGrpc(s.stub().OpenSession(s.Context().get(), open, &info)));
    t.session_id = info.session_id();
    t.case_id = info.case_id();
    std::printf("volume %s, session %s%s%s\n", t.volume.volume_id().c_str(), t.session_id.c_str(),
                t.case_id.empty() ? "" : ", case ", t.case_id.c_str());
    std::fflush(stdout);  // a watcher (a test, a script) learns the ids at once
    return t;
  }
  v3::ListSessionsResponse sessions;
  RETURN_IF_ERROR(FromGrpc(s.stub().ListSessions(s.Context().get(), {}, &sessions)));
  for (const auto& x : sessions.sessions()) {
    if (x.session_id() == session_id) {
      v3::GetVolumeRequest get;
      get.set_volume_id(x.volume_id());
      RETURN_IF_ERROR(FromGrpc(s.stub().GetVolume(s.Context().get(), get, &t.volume)));
    }
  }
  if (t.volume.volume_id().empty()) return absl::NotFoundError(StrCat("session ", session_id));
  return t;
}

// Plays the script. Behind a balancer the session's replica may die or be
// drained: the stream ends UNAVAILABLE (or NOT_FOUND on a replica without
// it). A session this command opened is then reopened where the balancer
// now sends the key (the volume reloaded from its source, or the case
// reopened), the script's events so far are replayed at once to restore the
// deformation, and the script goes on. `sessions`: every session used.
PlayResult PlayWithReopens(const ServerConnection& s, const Script& script,
                           const std::string& source, const PlayTarget& target,
                           PlayOptions& options, std::vector<std::string>& sessions) {
  const std::string& session_id = target.session_id;
  const std::string& case_id = target.case_id;
  const bool opened_here = target.opened_here;
  PlayResult result;
  const SteadyClock::time_point play_start = SteadyClock::now();
  for (int reopened = 0;; ++reopened) {
    const PlayResult segment = PlayScript(s, script, options);
    Append(segment, MsBetween(play_start, SteadyClock::now()) - segment.duration_ms, &result);
    if (segment.status.ok() || !SessionLost(segment.status)) break;
    if (!opened_here) {
      result.status = Status(segment.status.code(),
                             StrCat(segment.status.message(), " (session ", session_id,
                                    " given by --session cannot be reopened here: play without "
                                    "--session to have vpm reopen one)"));
      break;
    }
    if (reopened == kMaxReopens) break;
    std::fprintf(stderr,
                 "vpm play: session %s lost (%s: %s); reopening: %s reloaded where the "
                 "balancer sends key %s now, %lld events replayed\n",
                 options.session_id.c_str(),
                 std::string(absl::StatusCodeToString(segment.status.code())).c_str(),
                 std::string(segment.status.message()).c_str(), source.c_str(),
                 s.session_key().c_str(),
                 (long long)std::max(options.resume_at, segment.script_events_written));
    // A server that keeps cases reopens ours with what it holds: the script
    // goes on after the manipulations the case has, none sent twice.
    Result<ReopenedCase> in_case =
        case_id.empty() ? Result<ReopenedCase>(absl::FailedPreconditionError("no case"))
                        : ReopenCase(s, case_id);
    if (in_case.ok()) {
      options.skip_until = ResumeIndex(script, *in_case);
      options.resume_at = options.skip_until;
      options.session_id = in_case->session_id;
      sessions.push_back(in_case->session_id);
      std::fprintf(stderr, "vpm play: reopened case %s as session %s (%lld events kept)\n",
                   case_id.c_str(), in_case->session_id.c_str(), (long long)in_case->events);
      continue;
    }
    Result<std::string> reopened_id = Reopen(s, source);
    if (!reopened_id.ok()) {
      result.status = Status(reopened_id.status().code(),
                             StrCat("reopening after the loss of session ", options.session_id,
                                    ": ", reopened_id.status().message()));
      break;
    }
    options.resume_at = std::max(options.resume_at, segment.script_events_written);
    options.session_id = *reopened_id;
    sessions.push_back(*reopened_id);
    std::fprintf(stderr, "vpm play: reopened as session %s\n", reopened_id->c_str());
  }
  result.duration_ms = MsBetween(play_start, SteadyClock::now());
  return result;
}

// The play's figures: counts, rates and each latency's summary.
json PlayReport(const PlayResult& result, const std::string& session_id,
                const std::vector<std::string>& sessions) {
  std::vector<double> frame_latency, render, fem, warp, encode, intervals;
  const std::vector<double>& latency = result.event_latency_ms;
  int64_t bytes = 0, interactive = 0;
  for (size_t i = 0; i < result.frames.size(); ++i) {
    const FrameRecord& f = result.frames[i];
    if (f.latency_ms >= 0) frame_latency.push_back(f.latency_ms);
    render.push_back(f.timings.render_ms());
    fem.push_back(f.timings.fem_ms());
    warp.push_back(f.timings.warp_ms());
    encode.push_back(f.timings.encode_ms());
    if (i > 0) intervals.push_back(f.received_ms - result.frames[i - 1].received_ms);
    bytes += f.bytes;
    interactive += f.interactive;
  }
  const double seconds = result.duration_ms / 1000.0;
  return json{
      {"session_id", session_id},
      {"sessions", sessions},
      {"reopened", sessions.size() - 1},
      {"events", result.events_sent},
      {"frames", result.frames.size()},
      {"interactive_frames", interactive},
      {"duration_s", seconds},
      {"fps", seconds > 0 ? double(result.frames.size()) / seconds : 0.0},
      {"time_to_first_frame_ms", result.first_frame_ms},
      {"bytes_per_frame", result.frames.empty() ? 0 : bytes / int64_t(result.frames.size())},
      {"superseded", result.frames.empty() ? 0 : result.frames.back().superseded},
      {"latency_ms", Summarize(latency)},
      {"frame_latency_ms", Summarize(frame_latency)},
      {"frame_interval_ms", Summarize(intervals)},
      {"server_render_ms", Summarize(render)},
      {"server_fem_ms", Summarize(fem)},
      {"server_warp_ms", Summarize(warp)},
      {"server_encode_ms", Summarize(encode)}};
}

void PrintPlayReport(const json& report, const PlayResult& result, const std::string& out_dir,
                     const std::string& report_path) {
  const int64_t interactive = report["interactive_frames"].get<int64_t>();
  const double seconds = report["duration_s"].get<double>();
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
}

Status Play(const ServerConnection& s, const std::string& script_path, std::string session_id,
            const std::string& out_dir, std::string report_path) {
  // Ctrl-C stops the script, and the session opened here is still closed.
  CatchInterrupts();
  ASSIGN_OR_RETURN(json script_json, ReadJsonFile(script_path));
  const std::string source = script_json.value("volume", "phantom:abdomen?size=64");
  ASSIGN_OR_RETURN(const PlayTarget target, OpenOrFindSession(s, source, session_id));
  ASSIGN_OR_RETURN(Script script, ParseScript(script_json, target.volume));
  if (!out_dir.empty()) RETURN_IF_ERROR(MakeDirectories(out_dir));
  PlayOptions options;
  options.session_id = target.session_id;
  Status write_status;      // the first frame that could not be saved, reported at the end
  int64_t frame_index = 0;  // across reopened sessions
  options.on_frame = [&](const v3::Frame& frame, int64_t) {
    if (out_dir.empty() || !write_status.ok()) return;
    char name[64];
    std::snprintf(name, sizeof name, "frame_%04lld.%s", (long long)frame_index++,
                  std::string(EncodingExtension(frame.encoding())).c_str());
    write_status = WriteFile(fs::path(out_dir) / name, frame.image());
  };
  std::vector<std::string> sessions{target.session_id};
  const PlayResult result = PlayWithReopens(s, script, source, target, options, sessions);
  // The sessions this command opened go with it, whatever the outcome: every
  // one, not only the last (a session given up as lost may still exist, on
  // this replica or another; closing one that is gone is NOT_FOUND, which
  // changes nothing).
  if (target.opened_here) {
    for (const std::string& id : sessions) s.CloseSessionQuietly(id);
  }
  RETURN_IF_ERROR(result.status);
  RETURN_IF_ERROR(write_status);
  const json report = PlayReport(result, options.session_id, sessions);
  if (report_path.empty() && !out_dir.empty()) {
    report_path = (fs::path(out_dir) / "report.json").string();
  }
  if (!report_path.empty()) RETURN_IF_ERROR(WriteFile(report_path, report.dump(2) + "\n"));
  PrintPlayReport(report, result, out_dir, report_path);
  return absl::OkStatus();
}

}  // namespace

void AddPlayCommand(CLI::App& app, const ServerFlags* flags, int* exit_code) {
  struct PlayArgs {
    std::string script, session, out_dir, report;
  };
  auto a = std::make_shared<PlayArgs>();
  CLI::App* play = app.add_subcommand("play", "server: replay an interaction script over Interact");
  play->add_option("SCRIPT", a->script, "script JSON (see client/common/script_player.h)")->required();
  play->add_option("--session", a->session,
                   "play on this session (default: open one on the script's volume, closed at the end)");
  play->add_option("--out-dir", a->out_dir, "save frames and report.json here");
  play->add_option("--report", a->report, "timing report JSON");
  play->callback(WithServer(flags, exit_code, [a](const ServerConnection& s) {
    return Play(s, a->script, a->session, a->out_dir, a->report);
  }));
}

}  // namespace vpm::cli

#include "client/common/script_player.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "client/common/interrupt.h"
#include "proto/enum_names.h"
#include "server/common/clock.h"

namespace vpm::cli {
namespace {

v3::Vec3 Vec(double x, double y, double z) {
  v3::Vec3 v;
  v.set_x(x);
  v.set_y(y);
  v.set_z(z);
  return v;
}

Result<v3::Vec3> VecOf(const nlohmann::json& j, const char* what) {
  if (!j.is_array() || j.size() != 3) {
    return absl::InvalidArgumentError(StrCat(what, ": needs [x, y, z]"));
  }
  return Vec(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

// A script's "settings": size, mode, preset, encoding, overlay and the
// interactive quality. nlohmann::json throws on values of the wrong type.
Status ParseSettings(const nlohmann::json& s, v3::RenderSettings& settings) {
  settings.set_width(s.value("width", 256));
  settings.set_height(s.value("height", 256));
  const std::string mode = s.value("mode", "dvr");
  const auto mode_value = RenderModeFromName(mode);
  if (!mode_value) {
    return absl::InvalidArgumentError(StrCat("settings.mode: '", mode, "' is not dvr or mip"));
  }
  settings.set_mode(*mode_value);
  settings.set_preset(s.value("preset", ""));
  const std::string encoding = s.value("encoding", "jpeg");
  const auto encoding_value = EncodingFromName(encoding);
  if (!encoding_value) {
    return absl::InvalidArgumentError(
        StrCat("settings.encoding: '", encoding, "' is not jpeg or png"));
  }
  settings.set_encoding(*encoding_value);
  settings.set_jpeg_quality(s.value("jpeg_quality", 0));
  settings.set_overlay(s.value("overlay", false));
  if (s.contains("interactive_quality")) {
    const std::string quality = s["interactive_quality"].get<std::string>();
    const auto quality_value = InteractiveQualityFromName(quality);
    if (!quality_value) {
      return absl::InvalidArgumentError(StrCat("settings.interactive_quality: '", quality,
                                               "' is not auto, fast, balanced or sharp"));
    }
    settings.set_interactive_quality(*quality_value);
  }
  return absl::OkStatus();
}

// A script's steps, each into its events: the camera the camera and orbit
// steps move, and the interval every event waits after the one before.
class StepParser {
 public:
  StepParser(double interval_ms, const v3::VolumeInfo& volume, std::vector<ScriptEvent>& events)
      : interval_ms_(interval_ms), volume_(volume), events_(events) {}

  Status Parse(const nlohmann::json& step) {
    if (step.contains("camera")) {
      const auto& c = step["camera"];
      azimuth_ = c.value("azimuth_deg", 0.0);
      elevation_ = c.value("elevation_deg", 0.0);
      distance_ = c.value("distance_mm", 0.0);
      PushCamera();
    } else if (step.contains("orbit")) {
      Orbit(step["orbit"]);
    } else if (step.contains("grab")) {
      return Grab(step["grab"]);
    } else if (step.contains("drag")) {
      return Drag(step["drag"]);
    } else if (step.contains("pull")) {
      ScriptEvent e = Event();
      ASSIGN_OR_RETURN(*e.event.mutable_pull()->mutable_force_n(),
                       VecOf(step["pull"].at("force_n"), "pull.force_n"));
      events_.push_back(e);
    } else if (step.contains("release")) {
      const auto& r = step["release"];
      if (!r.is_object()) return absl::InvalidArgumentError("script: release must be an object");
      ScriptEvent e = Event();
      e.event.mutable_release()->set_keep(r.value("keep", false));
      events_.push_back(e);
    } else if (step.contains("wait_ms")) {
      if (!events_.empty()) events_.back().wait_ms += step["wait_ms"].get<double>();
    } else {
      return absl::InvalidArgumentError(StrCat("script step ", step.dump(), ": unknown"));
    }
    return absl::OkStatus();
  }

 private:
  ScriptEvent Event() const {
    ScriptEvent e;
    e.wait_ms = interval_ms_;
    return e;
  }

  void PushCamera() {
    ScriptEvent e = Event();
    e.event.mutable_camera()->set_azimuth_deg(azimuth_);
    e.event.mutable_camera()->set_elevation_deg(elevation_);
    e.event.mutable_camera()->set_distance_mm(distance_);
    events_.push_back(e);
  }

  // `steps` camera events from the current azimuth and elevation to the
  // orbit's.
  void Orbit(const nlohmann::json& o) {
    const int steps = o.value("steps", 10);
    const double from = azimuth_, to = o.value("to_azimuth_deg", azimuth_);
    const double el_from = elevation_, el_to = o.value("to_elevation_deg", elevation_);
    for (int i = 1; i <= steps; ++i) {
      azimuth_ = from + (to - from) * i / steps;
      elevation_ = el_from + (el_to - el_from) * i / steps;
      PushCamera();
    }
  }

  // At a landmark of the volume, a point (mm), or the volume's centre.
  Status Grab(const nlohmann::json& g) {
    ScriptEvent e = Event();
    v3::Grab* grab = e.event.mutable_grab();
    if (g.contains("landmark")) {
      const std::string name = g["landmark"].get<std::string>();
      const auto& marks = volume_.landmarks();
      const auto it = std::find_if(marks.rbegin(), marks.rend(),
                                   [&](const auto& l) { return l.name() == name; });
      if (it == marks.rend()) {
        return absl::NotFoundError(StrCat("grab.landmark '", name, "' is not in the volume"));
      }
      *grab->mutable_point_mm() = it->position_mm();
    } else if (g.contains("point_mm")) {
      ASSIGN_OR_RETURN(*grab->mutable_point_mm(), VecOf(g["point_mm"], "grab.point_mm"));
    } else {
      *grab->mutable_point_mm() = Vec((volume_.dims(0) - 1) * volume_.spacing_mm().x() / 2,
                                      (volume_.dims(1) - 1) * volume_.spacing_mm().y() / 2,
                                      (volume_.dims(2) - 1) * volume_.spacing_mm().z() / 2);
    }
    grab->set_radius_mm(g.value("radius_mm", 0.0));
    events_.push_back(e);
    return absl::OkStatus();
  }

  // `steps` drag events to to_mm, evenly.
  Status Drag(const nlohmann::json& d) {
    ASSIGN_OR_RETURN(v3::Vec3 to, VecOf(d.at("to_mm"), "drag.to_mm"));
    const int steps = d.value("steps", 10);
    for (int i = 1; i <= steps; ++i) {
      ScriptEvent e = Event();
      const double f = double(i) / steps;
      *e.event.mutable_drag()->mutable_offset_mm() = Vec(to.x() * f, to.y() * f, to.z() * f);
      events_.push_back(e);
    }
    return absl::OkStatus();
  }

  double interval_ms_;
  const v3::VolumeInfo& volume_;
  std::vector<ScriptEvent>& events_;
  double azimuth_ = 0, elevation_ = 0, distance_ = 0;
};

}  // namespace

Result<nlohmann::json> ReadJsonFile(const std::string& path) {
  std::ifstream file(path);
  if (!file) return absl::NotFoundError(StrCat(path, ": cannot read"));
  try {
    return nlohmann::json::parse(file);
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(StrCat(path, ": ", e.what()));
  }
}

nlohmann::json DefaultScriptJson() {
  return nlohmann::json::parse(R"({
    "volume": "phantom:abdomen?size=64",
    "settings": {"width": 256, "height": 256},
    "interval_ms": 33,
    "steps": [
      {"camera": {"azimuth_deg": -30, "elevation_deg": 10}},
      {"orbit": {"to_azimuth_deg": 30, "steps": 8}},
      {"grab": {"landmark": "liver"}},
      {"drag": {"to_mm": [0, -15, 10], "steps": 10}},
      {"wait_ms": 300},
      {"release": {}}
    ]})");
}

Result<Script> ParseScript(const nlohmann::json& j, const v3::VolumeInfo& volume) {
  Script script;
  try {
    if (j.contains("volume")) script.volume = j["volume"].get<std::string>();
    if (j.contains("settings")) RETURN_IF_ERROR(ParseSettings(j["settings"], script.settings));
    StepParser steps(j.value("interval_ms", 33.0), volume, script.events);
    for (const auto& step : j.at("steps")) RETURN_IF_ERROR(steps.Parse(step));
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(StrCat("script: ", e.what()));
  }
  return script;
}

namespace {

// One play of a script on an Interact stream: a reader thread records the
// frames (and each event's latency, from its send to the first frame that
// shows it) while this thread sends the events.
class ScriptRun {
 public:
  ScriptRun(const ServerConnection& server, const PlayOptions& options)
      : options_(options),
        context_(server.Context(/*streaming=*/true)),
        stream_(server.stub().Interact(context_.get())),
        start_(SteadyClock::now()) {}

  PlayResult Run(const Script& script) {
    // Reads until the server ends the stream; the sender half-closes once
    // the still frame of the last event has arrived.
    std::thread reader([this] { ReadFrames(); });
    v3::InteractRequest first;
    first.set_session_id(options_.session_id);
    *first.mutable_event()->mutable_settings() = script.settings;
    bool ok = Send(first, sequence_);
    bool grabbed = false;
    ok = SendEvents(script, ok, grabbed);
    if (Interrupted()) {
      // Ctrl-C: the stream is cancelled, nothing waits for a still frame.
      context_->TryCancel();
      reader.join();
      (void)stream_->Finish();
      result_.status = absl::CancelledError("interrupted (SIGINT/SIGTERM)");
      result_.duration_ms = MsBetween(start_, SteadyClock::now());
      return result_;
    }
    if (ok && grabbed) {
      v3::InteractRequest release;
      release.mutable_event()->mutable_release();
      ok = Send(release, ++sequence_);
    }
    WaitForTheLastStill(ok);
    stream_->WritesDone();
    reader.join();
    result_.status = FromStreamEnd(stream_->Finish());
    result_.duration_ms = MsBetween(start_, SteadyClock::now());
    return result_;
  }

 private:
  void ReadFrames() {
    v3::Frame frame;
    int64_t index = 0;
    while (stream_->Read(&frame)) {
      Record(frame, SteadyClock::now());
      if (options_.on_frame) options_.on_frame(frame, index++);
    }
    std::lock_guard lock(mutex_);
    final_seen_ = true;  // the stream ended: nothing more will come
    got_final_.notify_all();
  }

  void Record(const v3::Frame& frame, SteadyClock::time_point now) {
    FrameRecord record;
    record.received_ms = MsBetween(start_, now);
    record.last_sequence = frame.last_sequence();
    record.interactive = frame.interactive();
    record.bytes = static_cast<int64_t>(frame.image().size());
    record.timings = frame.timings();
    record.superseded = frame.superseded_frames();
    std::lock_guard lock(mutex_);
    auto it = sent_at_.find(frame.last_sequence());
    if (it != sent_at_.end()) record.latency_ms = MsBetween(it->second, now);
    for (auto e = sent_at_.upper_bound(shown_sequence_);
         e != sent_at_.end() && e->first <= frame.last_sequence(); ++e) {
      result_.event_latency_ms.push_back(MsBetween(e->second, now));
    }
    shown_sequence_ = std::max(shown_sequence_, frame.last_sequence());
    if (result_.first_frame_ms < 0) result_.first_frame_ms = record.received_ms;
    result_.frames.push_back(record);
    if (sending_done_ && frame.last_sequence() == last_sequence_ && !frame.interactive()) {
      final_seen_ = true;
      got_final_.notify_all();
    }
  }

  bool Send(v3::InteractRequest request, uint64_t sequence) {
    request.mutable_event()->set_sequence(sequence);
    {
      std::lock_guard lock(mutex_);
      sent_at_[sequence] = SteadyClock::now();
      last_sequence_ = sequence;
    }
    ++result_.events_sent;
    return stream_->Write(request);
  }

  // The script's events, each after its wait (none while catching up to
  // options.resume_at; those before options.skip_until not at all), looped
  // for options.duration_s; `grabbed`: whether a grab is held at the end.
  bool SendEvents(const Script& script, bool ok, bool& grabbed) {
    bool first_pass = true;
    do {
      for (size_t i = 0; i < script.events.size() && ok; ++i) {
        const ScriptEvent& e = script.events[i];
        const bool skipped = first_pass && static_cast<int64_t>(i) < options_.skip_until;
        const bool catching_up = static_cast<int64_t>(i) < options_.resume_at;
        if (!skipped && !catching_up &&
            !SleepUnlessInterrupted(std::chrono::microseconds(int64_t(e.wait_ms * 1000)))) {
          break;
        }
        if (e.event.has_grab()) grabbed = true;
        if (e.event.has_release()) grabbed = false;
        if (skipped) {
          result_.script_events_written = static_cast<int64_t>(i) + 1;
          continue;
        }
        v3::InteractRequest request;
        *request.mutable_event() = e.event;
        ok = Send(request, ++sequence_);
        if (ok) result_.script_events_written = static_cast<int64_t>(i) + 1;
      }
      first_pass = false;
    } while (ok && !Interrupted() && options_.duration_s > 0 &&
             MsBetween(start_, SteadyClock::now()) < options_.duration_s * 1000);
    return ok;
  }

  // Up to 60 s for the still frame of the last event; past that the stream
  // is cancelled.
  void WaitForTheLastStill(bool ok) {
    std::unique_lock lock(mutex_);
    sending_done_ = true;
    for (const FrameRecord& f : result_.frames) {
      if (f.last_sequence == last_sequence_ && !f.interactive) final_seen_ = true;
    }
    if (ok && !got_final_.wait_for(lock, std::chrono::seconds(60), [&] { return final_seen_; })) {
      context_->TryCancel();
    }
  }

  const PlayOptions& options_;
  std::unique_ptr<grpc::ClientContext> context_;
  std::unique_ptr<grpc::ClientReaderWriter<v3::InteractRequest, v3::Frame>> stream_;
  const SteadyClock::time_point start_;
  uint64_t sequence_ = 1;
  std::mutex mutex_;  // guards what follows, shared with the reader
  std::condition_variable got_final_;
  PlayResult result_;
  std::map<uint64_t, SteadyClock::time_point> sent_at_;
  uint64_t last_sequence_ = 0;
  uint64_t shown_sequence_ = 0;  // the newest event a frame has shown
  bool final_seen_ = false;
  bool sending_done_ = false;
};

}  // namespace

PlayResult PlayScript(const ServerConnection& server, const Script& script,
                      const PlayOptions& options) {
  return ScriptRun(server, options).Run(script);
}

nlohmann::json Summarize(std::vector<double> v) {
  nlohmann::json j;
  j["count"] = v.size();
  if (v.empty()) return j;
  std::sort(v.begin(), v.end());
  double sum = 0, sum2 = 0;
  for (double x : v) {
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / double(v.size());
  auto pct = [&](double p) {
    return v[std::min(v.size() - 1, size_t(std::ceil(p / 100.0 * double(v.size()))) - (p > 0 ? 1 : 0))];
  };
  j["fastest"] = v.front();
  j["slowest"] = v.back();
  j["average"] = mean;
  j["stddev"] = std::sqrt(std::max(0.0, sum2 / double(v.size()) - mean * mean));
  j["p50"] = pct(50);
  j["p90"] = pct(90);
  j["p95"] = pct(95);
  j["p99"] = pct(99);
  return j;
}

}  // namespace vpm::cli

// Plays an interaction script over one Interact stream and measures it:
// shared by `vpm play` (one run, frames saved) and `vpm-load` (many
// concurrent runs, looped for a duration).
//
// Script (JSON):
//   {"volume": "phantom:abdomen?size=64",            used when no session is given
//    "settings": {"width": 256, "height": 256, "mode": "dvr", "preset": "ct-soft-tissue",
//                 "encoding": "jpeg", "jpeg_quality": 85,
//                 "interactive_quality": "fast" | "balanced" | "sharp"},
//    "interval_ms": 33,                                pause between events
//    "steps": [
//      {"camera": {"azimuth_deg": 0, "elevation_deg": 10, "distance_mm": 0}},
//      {"orbit": {"to_azimuth_deg": 60, "steps": 10}},       camera moves in steps
//      {"grab": {"landmark": "liver"}}  or  {"grab": {"point_mm": [x, y, z], "radius_mm": 0}},
//      {"drag": {"to_mm": [dx, dy, dz], "steps": 10}},       drag path from 0 to to_mm
//      {"pull": {"force_n": [fx, fy, fz]}},
//      {"wait_ms": 300},
//      {"release": {"keep": false}}]}                  keep: the drag stays
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "client/common/server_connection.h"
#include "server/common/status.h"

namespace vpm::cli {

struct ScriptEvent {
  v3::ClientEvent event;  // sequence filled in when sent
  double wait_ms = 0;     // pause before sending
};

struct Script {
  std::string volume = "phantom:abdomen?size=64";
  v3::RenderSettings settings;
  std::vector<ScriptEvent> events;
};

// Landmarks are resolved against `volume` (from GetVolume/LoadVolume).
Result<Script> ParseScript(const nlohmann::json& json, const v3::VolumeInfo& volume);
Result<nlohmann::json> ReadJsonFile(const std::string& path);
// A default script: orbit, grab at the centre, drag, release.
nlohmann::json DefaultScriptJson();

struct FrameRecord {
  double received_ms = 0;     // since the stream started
  // From sending last_sequence's event to receipt, for every frame (a still
  // that shows an event again counts too; PlayResult::event_latency_ms
  // counts each event once).
  double latency_ms = -1;
  uint64_t last_sequence = 0;
  bool interactive = false;
  int64_t bytes = 0;
  v3::StageTimings timings;
  uint64_t superseded = 0;
};

struct PlayResult {
  Status status;  // a stream cut by a balancer reads UNAVAILABLE (FromStreamEnd)
  std::vector<FrameRecord> frames;
  // Event to frame: per event, from sending it to the first frame that shows
  // it (last_sequence >= its sequence), ms. An event that a newer one
  // replaced in the server's queue counts until the frame of the newer one.
  std::vector<double> event_latency_ms;
  double first_frame_ms = -1;  // time to first frame
  double duration_ms = 0;
  int64_t events_sent = 0;
  int64_t script_events_written = 0;  // of script.events, counting from 0 (not resume_at)
};

struct PlayOptions {
  std::string session_id;
  double duration_s = 0;  // 0: play once; else loop the events until then
  // Script events before this index are sent at once, without their waits
  // (a reopened session catches up with the deformation), then the script
  // goes on from here.
  int64_t resume_at = 0;
  // Script events before this index are not sent at all (a reopened case
  // holds them already), then the script goes on from here; first pass only.
  int64_t skip_until = 0;
  // Called for each frame (e.g. to save it); may be empty.
  std::function<void(const v3::Frame&, int64_t index)> on_frame;
};

// Opens an Interact stream on options.session_id, plays the script, waits
// for the still frame that reflects the last event, and closes.
PlayResult PlayScript(const ServerConnection& server, const Script& script,
                      const PlayOptions& options);

// Summary statistics over values (ms): count, min, max, mean, p50/90/95/99, stddev.
nlohmann::json Summarize(std::vector<double> values);

}  // namespace vpm::cli

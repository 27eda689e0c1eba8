// What the case store keeps of a case (docs/CASES.md): its row and its
// events. Plain data; the store fills it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/scene/scene_op.h"

namespace vpm::cases {

struct CaseRecord {
  std::string id;
  std::string owner;
  std::string title;
  std::string notes;
  // Where its volume comes from: a LoadVolumeRequest.source (a data-root
  // path, phantom:..., pacs:...), or upload:SHA256 for an upload.
  std::string source;
  std::string mesh_params;  // a serialized vpm.v3.MeshParams (world LPS)
  std::string camera;       // a serialized vpm.v3.Camera; empty: the default
  // A serialized vpm.v3.RenderSettings, the view a client of its session
  // last set (no size or encoding: each client's own); empty: none.
  std::string render_settings;
  std::vector<std::string> shared_with;
  int64_t events = 0;  // events in effect
  int64_t undone = 0;  // events undone (redo brings them back)
  double max_displacement_mm = 0.0;  // after the last event in effect, as stored
  int64_t created_ms = 0;   // Unix time, ms
  int64_t modified_ms = 0;  // Unix time, ms
};

// One acknowledged manipulation: `seq` counts from 1 within its case.
struct CaseEvent {
  int64_t seq = 0;
  SceneOp op;
  int64_t time_ms = 0;  // Unix time, ms
  // A still frame settled the bounded drag after this event, before the
  // next (MarkSettled): a replay settles there too.
  bool settled = false;
};

// The ops a scene at rest replays to reach the state of `events` (in effect,
// in order): each op, and a kSettle after each settled event.
std::vector<SceneOp> ReplayLog(const std::vector<CaseEvent>& events);

}  // namespace vpm::cases

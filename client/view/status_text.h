// The status bar's two lines, from the newest frame and the stream meters.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

struct StatusInputs {
  double fps = 0;                    // frames per second received
  std::optional<double> latency_ms;  // newest event-to-frame round trip
  std::optional<v3::Frame> frame;    // the frame shown (image bytes not needed)
  bool grab_mode = false;
  bool grabbed = false;
  // RenderSettings.interactive_quality, shown after the frame size as fast,
  // bal or sharp, auto when unspecified (the server's device chooses).
  v3::InteractiveQuality interactive_quality = v3::INTERACTIVE_QUALITY_UNSPECIFIED;
};

// Short enough for a 256-pixel-wide window at scale 1 (41 characters):
//   "12.5 fps  rtt 85 ms  256x256 fast"
//   "still  disp 3.2 mm  GRAB MODE"
//   "server ms fem 10 warp 2 rend 45"      (the server's stage times)
//   "enc 1 queue 0 total 60  F1/h: help"
inline constexpr int kStatusLineCount = 4;
std::array<std::string, kStatusLineCount> StatusLines(const StatusInputs& in);

}  // namespace vpm::view

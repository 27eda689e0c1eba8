#include "client/view/status_text.h"

#include <cstdio>

namespace vpm::view {
namespace {

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

}  // namespace

std::array<std::string, kStatusLineCount> StatusLines(const StatusInputs& in) {
  std::string rate = Format("%.1f fps", in.fps);
  rate += in.latency_ms ? Format("  rtt %.0f ms", *in.latency_ms) : std::string("  rtt -");
  std::string state, stages = "server ms", more;
  if (in.frame) {
    const v3::Frame& f = *in.frame;
    rate += "  " + std::to_string(f.width()) + "x" + std::to_string(f.height());
    switch (in.interactive_quality) {
      case v3::INTERACTIVE_QUALITY_FAST: rate += " fast"; break;
      case v3::INTERACTIVE_QUALITY_BALANCED: rate += " bal"; break;
      case v3::INTERACTIVE_QUALITY_SHARP: rate += " sharp"; break;
      default:
        rate += " auto";
        break;
    }
    // Refinement at rest: the rungs before the still.
    state = f.refine_level() > 0   ? "refine " + std::to_string(f.refine_level())
            : f.interactive()      ? "interactive"
                                   : "still";
    state += Format("  disp %.1f mm", f.max_displacement_mm());
    // Shown when there is something to say: the grabbed tissue behind the
    // pointer, or (never expected) inverted tets.
    if (f.lag_mm() >= 0.05) state += Format("  lag %.1f", f.lag_mm());
    if (f.inverted_tets() > 0) state += Format("  INV %d", static_cast<int>(f.inverted_tets()));
    const v3::StageTimings& t = f.timings();
    stages += Format(" fem %.0f", t.fem_ms()) + Format(" warp %.0f", t.warp_ms()) +
              Format(" rend %.0f", t.render_ms());
    more = Format("enc %.0f", t.encode_ms()) + Format(" queue %.0f", t.queue_ms()) +
           Format(" total %.0f", t.total_ms()) + "  ";
  } else {
    state = "no frame yet";
    stages += " -";
  }
  if (in.grab_mode) state += in.grabbed ? "  GRABBED" : "  GRAB MODE";
  more += "F1/h: help";
  return {rate, state, stages, more};
}

}  // namespace vpm::view

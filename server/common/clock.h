// Timing on the monotonic clock, in milliseconds: the one helper every
// stage, benchmark and client uses for the per-stage times it reports.
#pragma once

#include <chrono>

namespace vpm {

using SteadyClock = std::chrono::steady_clock;

// Milliseconds from t0 to t1 (negative when t1 is earlier).
inline double MsBetween(SteadyClock::time_point t0, SteadyClock::time_point t1) {
  return std::chrono::duration<double, std::milli>(t1 - t0).count();
}

// Milliseconds from t0 to now.
inline double MsSince(SteadyClock::time_point t0) { return MsBetween(t0, SteadyClock::now()); }

}  // namespace vpm

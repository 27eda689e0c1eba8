// Small helpers for the benchmark programs: wall-clock timing and the
// minimum over repetitions (the figure least disturbed by other processes).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>

#include "absl/status/statusor.h"
#include "server/common/clock.h"

namespace vpm::bench {

// Runs fn `reps` times; returns the fastest wall time in ms.
inline double MinMs(int reps, const std::function<void()>& fn) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    best = std::min(best, MsSince(t0));
  }
  return best;
}

// Unwraps a Result, or aborts the benchmark with a message.
template <typename T>
T Check(absl::StatusOr<T> result, const char* what) {
  if (!result.ok()) {
    std::fprintf(stderr, "bench: %s failed: %s\n", what,
                 std::string(result.status().message()).c_str());
    std::exit(1);
  }
  return std::move(result).value();
}

}  // namespace vpm::bench

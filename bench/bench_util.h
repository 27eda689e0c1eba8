// Small helpers for the benchmark programs: wall-clock timing and the
// minimum over repetitions (the figure least disturbed by other processes).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/common/clock.h"

namespace vpm::bench {

// Mean squared difference over R, G and B of two RGBA8 images of one size
// (alpha left out), in grey levels squared.
inline double RgbMse(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double sum = 0.0;
  int64_t n = 0;
  for (size_t i = 0; i + 3 < a.size() && i + 3 < b.size(); i += 4) {
    for (int c = 0; c < 3; ++c) {
      const double d = double(a[i + c]) - double(b[i + c]);
      sum += d * d;
      ++n;
    }
  }
  return n == 0 ? 0.0 : sum / double(n);
}

// PSNR in dB of an MSE over 8-bit values; 99 for identical images.
inline double PsnrOfMse(double mse) {
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

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

// The same for a call that returns no value.
inline void Check(const absl::Status& status, const char* what) {
  if (!status.ok()) {
    std::fprintf(stderr, "bench: %s failed: %s\n", what, std::string(status.message()).c_str());
    std::exit(1);
  }
}

}  // namespace vpm::bench

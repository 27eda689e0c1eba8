// A progress bar on a terminal line for long client work (loads, exports,
// mesh builds): "loading ct.nii [########------------]  40%  reading  1.3 s".
// Drawn only when enabled (stderr is a terminal, or --progress) and only
// once the work has run `delay` (a second by default), so that quick
// commands print nothing; redrawn at most every 100 ms; the line is ended
// when the bar is finished or destroyed. Thread-safe.
#pragma once

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <string_view>

#include "server/common/progress.h"

namespace vpm::cli {

// True when `--progress` was given or stderr is a terminal.
bool ProgressWanted(bool forced);

class ProgressBar {
 public:
  ProgressBar(std::string label, bool enabled, std::FILE* out = stderr,
              std::chrono::milliseconds delay = std::chrono::seconds(1));
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // Reports into this bar (fractions clamped to [0, 1], never decreasing);
  // valid while the bar lives.
  ProgressFn Reporter();
  void Update(double fraction, std::string_view stage);
  // Draws the final state (if anything was drawn) and ends the line.
  void Finish();

  double fraction() const;  // the largest fraction reported

 private:
  void DrawLocked(std::chrono::steady_clock::time_point now);

  std::string label_;
  bool enabled_;
  std::FILE* out_;
  std::chrono::milliseconds delay_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_draw_{};
  mutable std::mutex mutex_;
  double fraction_ = 0.0;
  std::string stage_;
  bool drawn_ = false;
  bool finished_ = false;
};

}  // namespace vpm::cli

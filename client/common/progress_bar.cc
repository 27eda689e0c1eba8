#include "client/common/progress_bar.h"

#include <algorithm>
#include <cmath>

#include <unistd.h>

namespace vpm::cli {
namespace {

constexpr int kBarWidth = 24;  // characters between the brackets
constexpr auto kRedrawEvery = std::chrono::milliseconds(100);

}  // namespace

bool ProgressWanted(bool forced) { return forced || isatty(STDERR_FILENO) == 1; }

ProgressBar::ProgressBar(std::string label, bool enabled, std::FILE* out,
                         std::chrono::milliseconds delay)
    : label_(std::move(label)), enabled_(enabled), out_(out), delay_(delay) {}

ProgressBar::~ProgressBar() { Finish(); }

ProgressFn ProgressBar::Reporter() {
  return [this](double fraction, std::string_view stage) { Update(fraction, stage); };
}

double ProgressBar::fraction() const {
  std::lock_guard lock(mutex_);
  return fraction_;
}

void ProgressBar::Update(double fraction, std::string_view stage) {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  fraction_ = std::max(fraction_, std::clamp(fraction, 0.0, 1.0));
  stage_ = std::string(stage);
  const auto now = std::chrono::steady_clock::now();
  if (!enabled_ || now - start_ < delay_ || now - last_draw_ < kRedrawEvery) return;
  DrawLocked(now);
}

void ProgressBar::Finish() {
  std::lock_guard lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (!drawn_) return;
  DrawLocked(std::chrono::steady_clock::now());
  std::fputc('\n', out_);
  std::fflush(out_);
}

void ProgressBar::DrawLocked(std::chrono::steady_clock::time_point now) {
  const int filled = static_cast<int>(std::floor(fraction_ * kBarWidth));
  const std::string bar = std::string(filled, '#') + std::string(kBarWidth - filled, '-');
  const double seconds = std::chrono::duration<double>(now - start_).count();
  // \r and a cleared tail: the line is rewritten in place.
  std::fprintf(out_, "\r%s [%s] %3d%%  %-12s %5.1f s\x1b[K", label_.c_str(), bar.c_str(),
               static_cast<int>(std::floor(fraction_ * 100.0)), stage_.c_str(), seconds);
  std::fflush(out_);
  last_draw_ = now;
  drawn_ = true;
}

}  // namespace vpm::cli

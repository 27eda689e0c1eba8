#include "client/view/stream_meters.h"

#include <algorithm>
#include <cmath>

#include "server/common/clock.h"

namespace vpm::view {

void FrameRateMeter::OnFrame(SteadyClock::time_point t) {
  times_.push_back(t);
  while (times_.size() > 2 && t - times_.front() > window_) times_.pop_front();
}

double FrameRateMeter::Fps(SteadyClock::time_point now) const {
  if (times_.size() < 2 || now - times_.back() > window_) return 0.0;
  const double span_s = std::chrono::duration<double>(times_.back() - times_.front()).count();
  return span_s > 0 ? double(times_.size() - 1) / span_s : 0.0;
}

void LatencyMeter::Sent(uint64_t sequence, SteadyClock::time_point t) { sent_[sequence] = t; }

std::optional<double> LatencyMeter::Received(uint64_t last_sequence, SteadyClock::time_point t) {
  auto end = sent_.upper_bound(last_sequence);
  if (end == sent_.begin()) return std::nullopt;
  const SteadyClock::time_point newest = std::prev(end)->second;
  sent_.erase(sent_.begin(), end);
  return MsBetween(newest, t);
}

bool RetryCanSucceed(const Status& status) {
  switch (status.code()) {
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kNotFound:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kPermissionDenied:
    case absl::StatusCode::kUnauthenticated:
    case absl::StatusCode::kUnimplemented:
    case absl::StatusCode::kAlreadyExists:
    case absl::StatusCode::kDataLoss:
      return false;
    default:
      return true;
  }
}

double ReconnectBackoffS(int attempt) {
  return std::min(5.0, 0.25 * std::pow(2.0, std::clamp(attempt, 0, 10)));
}

}  // namespace vpm::view

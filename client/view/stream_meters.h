// What the status bar measures about the frame stream: frames per second
// over a sliding window, and the round-trip latency from sending an event
// to receiving the first frame whose last_sequence covers it.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>

#include "server/common/clock.h"
#include "server/common/status.h"

namespace vpm::view {

class FrameRateMeter {
 public:
  explicit FrameRateMeter(std::chrono::milliseconds window = std::chrono::milliseconds(1000))
      : window_(window) {}
  void OnFrame(SteadyClock::time_point t);
  // Frames per second over the window ending at `now`; 0 before two frames.
  double Fps(SteadyClock::time_point now) const;

 private:
  std::chrono::milliseconds window_;
  std::deque<SteadyClock::time_point> times_;
};

class LatencyMeter {
 public:
  void Sent(uint64_t sequence, SteadyClock::time_point t);
  // Latency (ms) of the newest sent event that `last_sequence` covers and no
  // earlier frame did; empty when this frame shows nothing new.
  std::optional<double> Received(uint64_t last_sequence, SteadyClock::time_point t);
  void Reset() { sent_.clear(); }

 private:
  std::map<uint64_t, SteadyClock::time_point> sent_;  // not yet covered by a frame
};

// Seconds to wait before reconnect attempt `attempt` (0-based): 0.25 s,
// doubling, at most 5 s.
double ReconnectBackoffS(int attempt);

// Whether opening the view (LoadVolume, OpenSession, joining --session) may
// succeed if tried again after `status`: the server down, busy or slow
// (Unavailable, ResourceExhausted, DeadlineExceeded, Aborted, Internal,
// Unknown, Cancelled) may pass; a bad or missing volume or session, a
// refused token or permission (InvalidArgument, NotFound, OutOfRange,
// FailedPrecondition, PermissionDenied, Unauthenticated, Unimplemented,
// AlreadyExists, DataLoss) will fail the same way every time.
bool RetryCanSucceed(const Status& status);

}  // namespace vpm::view

// Events waiting to be written to the Interact stream. The window thread
// pushes at mouse rate; the writer thread pops. A camera move, a drag or a
// settings change replaces one of the same kind still waiting at the tail
// (the newest wins, as on the server), so a slow link never builds a
// backlog; grabs and releases are never merged, so order is kept.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>

#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

class OutboundEvents {
 public:
  void Push(const v3::ClientEvent& event);
  // The oldest event, waiting up to `timeout`; empty on timeout or once
  // Close() was called.
  std::optional<v3::ClientEvent> Pop(std::chrono::milliseconds timeout);
  // Drops everything waiting (the stream they were meant for is gone).
  void Clear();
  // Wakes a waiting Pop; later Pops return at once until Reopen().
  void Close();
  void Reopen();
  size_t size() const;

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<v3::ClientEvent> events_;
  bool closed_ = false;
};

// Whether `b`, arriving right after `a`, can replace it.
bool Coalesces(const v3::ClientEvent& a, const v3::ClientEvent& b);

}  // namespace vpm::view

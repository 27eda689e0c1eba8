#include "client/view/outbound_events.h"

namespace vpm::view {

bool Coalesces(const v3::ClientEvent& a, const v3::ClientEvent& b) {
  if (a.event_case() != b.event_case()) return false;
  switch (a.event_case()) {
    case v3::ClientEvent::kCamera:
    case v3::ClientEvent::kDrag:
    case v3::ClientEvent::kSettings:
    case v3::ClientEvent::kPull:
      return !a.want_vertices() || b.want_vertices();
    default:
      return false;
  }
}

void OutboundEvents::Push(const v3::ClientEvent& event) {
  {
    std::lock_guard lock(mutex_);
    if (!events_.empty() && Coalesces(events_.back(), event)) {
      events_.back() = event;
    } else {
      events_.push_back(event);
    }
  }
  changed_.notify_one();
}

std::optional<v3::ClientEvent> OutboundEvents::Pop(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  changed_.wait_for(lock, timeout, [this] { return closed_ || !events_.empty(); });
  if (closed_ || events_.empty()) return std::nullopt;
  v3::ClientEvent event = std::move(events_.front());
  events_.pop_front();
  return event;
}

void OutboundEvents::Clear() {
  std::lock_guard lock(mutex_);
  events_.clear();
}

void OutboundEvents::Close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  changed_.notify_all();
}

void OutboundEvents::Reopen() {
  std::lock_guard lock(mutex_);
  closed_ = false;
}

size_t OutboundEvents::size() const {
  std::lock_guard lock(mutex_);
  return events_.size();
}

}  // namespace vpm::view

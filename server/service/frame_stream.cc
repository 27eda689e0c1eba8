#include "server/service/frame_stream.h"

#include <chrono>

#include "server/common/clock.h"
#include "server/service/grpc_status.h"

namespace vpm::service {
std::shared_ptr<FrameStream> FrameStream::Create(ServiceContext* service,
                                                 std::shared_ptr<Session> session,
                                                 StreamSettings settings, FrameSink* sink,
                                                 const Options& options) {
  return std::shared_ptr<FrameStream>(
      new FrameStream(service, std::move(session), std::move(settings), sink, options));
}

FrameStream::FrameStream(ServiceContext* service, std::shared_ptr<Session> session,
                         StreamSettings settings, FrameSink* sink, const Options& options)
    : service_(service),
      session_(std::move(session)),
      options_(options),
      sink_(sink),
      settings_(std::move(settings)) {}

void FrameStream::Attach() {
  std::weak_ptr<FrameStream> weak = weak_from_this();
  observer_token_ = session_->AddObserver([weak](bool closed) {
    if (auto self = weak.lock()) {
      if (closed) {
        self->Finish(grpc::Status(grpc::FAILED_PRECONDITION, "the session was closed"));
      } else {
        self->RequestFrame();
      }
    }
  });
  RequestFrame();
}

void FrameStream::EnqueueEvent(const v3::ClientEvent& event) {
  auto lock = Lock();
  if (finish_) return;
  const auto kind = event.event_case();
  const bool replaceable = kind == v3::ClientEvent::kCamera || kind == v3::ClientEvent::kDrag;
  last_event_at_ = std::chrono::steady_clock::now();
  if (replaceable && !events_.empty() && events_.back().event_case() == kind) {
    const bool want_vertices = events_.back().want_vertices() || event.want_vertices();
    events_.back() = event;
    events_.back().set_want_vertices(want_vertices);
  } else if (events_.size() >= kMaxQueuedEvents) {
    return FinishLocked(grpc::Status(grpc::RESOURCE_EXHAUSTED,
                                     "event: too many events waiting to be applied"));
  } else {
    events_.push_back(event);
  }
  if (applying_) return;
  applying_ = true;
  auto self = shared_from_this();
  if (!PostToPool([self] { self->ApplyQueued(); })) {
    applying_ = false;
    FinishLocked(grpc::Status(grpc::UNAVAILABLE, "the server is shutting down"));
  }
}

void FrameStream::ReadNext() {
  auto lock = Lock();
  if (!finish_ && sink_ != nullptr) outbox_.push_back({SinkCall::Kind::kRead});
}

void FrameStream::ApplyQueued() {
  while (true) {
    v3::ClientEvent event;
    {
      auto lock = Lock();
      if (events_.empty() || finish_) {
        events_.clear();
        applying_ = false;
        if (finish_after_events_) FinishLocked(*finish_after_events_);
        return;
      }
      event = std::move(events_.front());
      events_.pop_front();
    }
    if (event.has_settings()) {
      auto settings = ToStreamSettings(event.settings(), session_->volume().volume,
                                       service_->options.max_frame_side);
      if (!settings.ok()) return Finish(ToGrpcStatus(settings.status()));
      // The owner's settings are the session's view, which its case keeps
      // (Watch sends no events: a viewer's settings are never kept).
      if (options_.role == SessionRole::kOwner) session_->KeepView(event.settings());
      auto lock = Lock();
      settings_ = *std::move(settings);
    }
    SceneView view;
    {
      auto lock = Lock();
      view = settings_.view;
    }
    auto applied = session_->Apply(event, &view);
    if (!applied.ok()) return Finish(ToGrpcStatus(applied.status()));
    auto lock = Lock();
    if (event.sequence() > stream_sequence_) stream_sequence_ = event.sequence();
    if (event.want_vertices()) want_vertices_ = true;
    dirty_ = true;
    ScheduleLocked();
  }
}

void FrameStream::RequestFrame() {
  auto lock = Lock();
  dirty_ = true;
  ScheduleLocked();
}

void FrameStream::ScheduleLocked() {
  if (render_scheduled_ || finish_ || sink_ == nullptr || !dirty_) return;
  render_scheduled_ = true;
  auto self = shared_from_this();
  const auto queued_at = std::chrono::steady_clock::now();
  if (!PostToPool([self, queued_at] { self->RenderNow(queued_at); })) {
    render_scheduled_ = false;
  }
}

void FrameStream::RenderNow(std::chrono::steady_clock::time_point queued_at) {
  const double queue_ms = MsSince(queued_at);
  StreamSettings settings;
  bool want_vertices = false;
  // Interactive while the client is interacting (ClientActiveLocked);
  // StillCheck forces the still frame once it has been idle for
  // --still-delay-ms.
  const bool session_changing = session_->RecentlyChanged();
  bool interactive = false;
  uint64_t sequence = 0;
  {
    auto lock = Lock();
    if (finish_ || sink_ == nullptr) {
      render_scheduled_ = false;
      return;
    }
    dirty_ = false;
    settings = settings_;
    want_vertices = want_vertices_;
    want_vertices_ = false;
    sequence = stream_sequence_;  // events applied before this render starts
    // A client that became active since the still was asked for gets an
    // interactive frame first; the still check comes again after it.
    interactive = ClientActiveLocked() || (!force_still_ && session_changing);
    force_still_ = false;
  }
  // A stream that ends meanwhile (client gone, session closed, shutdown)
  // stops its still after the band in progress.
  const CancelToken cancel([this]() -> Status {
    if (finishing_.load(std::memory_order_relaxed)) {
      return absl::CancelledError("the stream ended");
    }
    return service_->WorkAllowed();
  });
  auto frame = session_->Render({&settings, std::nullopt, interactive, want_vertices, cancel});
  auto lock = Lock();
  render_scheduled_ = false;
  if (!frame.ok()) return FinishLocked(ToGrpcStatus(frame.status()));
  auto out = std::make_unique<v3::Frame>(*std::move(frame));
  out->mutable_timings()->set_queue_ms(queue_ms);
  out->mutable_timings()->set_total_ms(out->timings().total_ms() + queue_ms);
  if (options_.per_stream_sequence) out->set_last_sequence(sequence);
  last_interactive_ = out->interactive();
  DeliverLocked(std::move(out));
  if (dirty_) {
    ScheduleLocked();
  } else if (last_interactive_) {
    std::weak_ptr<FrameStream> weak = weak_from_this();
    service_->render_pool->PostAfter(
        std::chrono::milliseconds(int64_t(service_->options.still_delay_ms) + 5), [weak] {
          if (auto self = weak.lock()) self->StillCheck();
        });
  }
}

bool FrameStream::ClientActiveLocked() const {
  if (!events_.empty() || applying_) return true;
  return last_event_at_ != std::chrono::steady_clock::time_point{} &&
         MsSince(last_event_at_) < service_->options.still_delay_ms;
}

void FrameStream::StillCheck() {
  auto lock = Lock();
  if (!last_interactive_ || render_scheduled_ || finish_) return;
  if (session_->RecentlyChanged() || ClientActiveLocked()) {
    // Events still coming: look again later.
    still_deferrals_ = 0;
    std::weak_ptr<FrameStream> weak = weak_from_this();
    service_->render_pool->PostAfter(
        std::chrono::milliseconds(int64_t(service_->options.still_delay_ms) + 5), [weak] {
          if (auto self = weak.lock()) self->StillCheck();
        });
    return;
  }
  // Interactive work first: while other jobs wait for the render pool
  // (other streams' events and frames), the still waits a little, at most
  // kMaxStillDeferrals times, rather than hold the renderer ahead of them.
  if (service_->render_pool->queued() > 0 && still_deferrals_ < kMaxStillDeferrals) {
    ++still_deferrals_;
    std::weak_ptr<FrameStream> weak = weak_from_this();
    service_->render_pool->PostAfter(kStillDeferral, [weak] {
      if (auto self = weak.lock()) self->StillCheck();
    });
    return;
  }
  still_deferrals_ = 0;
  force_still_ = true;
  dirty_ = true;
  ScheduleLocked();
}

void FrameStream::DeliverLocked(std::unique_ptr<v3::Frame> frame) {
  if (sink_ == nullptr || finish_) return;
  frame->set_frame_number(++frame_number_);
  if (write_in_flight_) {
    if (pending_) {
      ++superseded_;
      service_->metrics->Superseded();
    }
    pending_ = std::move(frame);
    return;
  }
  WriteLocked(std::move(frame));
}

void FrameStream::WriteLocked(std::unique_ptr<v3::Frame> frame) {
  if (Status access = session_->access().Check(options_.user, options_.role, session_->id());
      !access.ok()) {
    return FinishLocked(ToGrpcStatus(access));
  }
  frame->set_superseded_frames(superseded_);
  service_->metrics->FrameSent(frame->timings());
  current_ = std::move(frame);
  write_in_flight_ = true;
  outbox_.push_back({SinkCall::Kind::kWrite, current_.get()});
}

void FrameStream::OnWriteDone(bool ok) {
  auto lock = Lock();
  write_in_flight_ = false;
  if (!ok) {
    // The client is gone; OnCancel / OnDone follow.
    pending_.reset();
    if (finish_ && !finished_ && sink_ != nullptr) {
      finished_ = true;
      outbox_.push_back({SinkCall::Kind::kFinish, nullptr, *finish_});
    }
    return;
  }
  if (finish_) {
    if (!finished_ && sink_ != nullptr) {
      finished_ = true;
      outbox_.push_back({SinkCall::Kind::kFinish, nullptr, *finish_});
    }
    return;
  }
  if (pending_ && sink_ != nullptr) WriteLocked(std::move(pending_));
}

void FrameStream::FinishAfterEvents(const grpc::Status& status) {
  auto lock = Lock();
  if (applying_ || !events_.empty()) {
    finish_after_events_ = status;
  } else {
    FinishLocked(status);
  }
}

void FrameStream::Finish(const grpc::Status& status) {
  auto lock = Lock();
  FinishLocked(status);
}

void FrameStream::FinishLocked(const grpc::Status& status) {
  if (finish_) return;
  finish_ = status;
  finishing_.store(true, std::memory_order_relaxed);
  pending_.reset();
  if (!write_in_flight_ && sink_ != nullptr) {
    finished_ = true;
    outbox_.push_back({SinkCall::Kind::kFinish, nullptr, status});
  }
}

bool FrameStream::PostToPool(std::function<void()> task) {
  // This stream's own lane: it takes its turn beside every other stream and
  // every user's unary calls, however many of those are queued.
  return service_->render_pool
      ->Submit(Job{.lane = StrCat("stream:", reinterpret_cast<uintptr_t>(this)),
                   .run = std::move(task),
                   .capped = false})
      .ok();
}

void FrameStream::Flush() {
  std::unique_lock lock(mutex_);
  if (flushing_) return;
  flushing_ = true;
  while (!outbox_.empty() && sink_ != nullptr) {
    const SinkCall call = std::move(outbox_.front());
    outbox_.pop_front();
    // The sink stays valid: OnDone (and Detach) can only follow the Finish
    // made here, and nothing is decided after a Finish.
    FrameSink* sink = sink_;
    lock.unlock();
    switch (call.kind) {
      case SinkCall::Kind::kWrite: sink->WriteFrame(call.frame); break;
      case SinkCall::Kind::kRead: sink->ReadNext(); break;
      case SinkCall::Kind::kFinish: sink->FinishStream(call.status); break;
    }
    lock.lock();
  }
  outbox_.clear();
  flushing_ = false;
}

void FrameStream::Detach() {
  {
    std::lock_guard lock(mutex_);
    sink_ = nullptr;
    pending_.reset();
    outbox_.clear();
  }
  session_->RemoveObserver(observer_token_);
}

uint64_t FrameStream::superseded() const {
  std::lock_guard lock(mutex_);
  return superseded_;
}

}  // namespace vpm::service

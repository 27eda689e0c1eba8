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
  events_received_.fetch_add(1, std::memory_order_relaxed);
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

FrameStream::FramePlan FrameStream::PlanLocked(bool session_changing) {
  FramePlan plan;
  dirty_ = false;
  plan.settings = settings_;
  plan.want_vertices = want_vertices_;
  want_vertices_ = false;
  plan.sequence = stream_sequence_;  // events applied before this render starts
  // Interactive while the client is interacting (ClientActiveLocked); a
  // client that became active since StillCheck found it at rest gets an
  // interactive frame first, and the still check comes again after it.
  plan.interactive =
      answer_move_ || ClientActiveLocked() || (!force_still_ && session_changing);
  answer_move_ = false;
  // The frame refines when the one before was cast while moving (or was a
  // rung): the ladder goes on where StillCheck (or the rung before) asked
  // for it, and starts over where the state changed since.
  plan.at_rest = !plan.interactive && (force_still_ || last_interactive_);
  if (!plan.at_rest || !force_still_) {
    ladder_.clear();
    next_rung_ = 0;
  }
  force_still_ = false;
  return plan;
}

void FrameStream::RenderNow(std::chrono::steady_clock::time_point queued_at) {
  const double queue_ms = MsSince(queued_at);
  const bool session_changing = session_->RecentlyChanged();
  const uint64_t version = session_->version();
  const uint64_t events = events_received_.load(std::memory_order_relaxed);
  FramePlan plan;
  {
    auto lock = Lock();
    if (finish_ || sink_ == nullptr) {
      render_scheduled_ = false;
      return;
    }
    plan = PlanLocked(session_changing);
  }
  // At rest: the ladder's rungs, then the still (ladder_ and next_rung_ are
  // the render task's: at most one runs per stream).
  if (plan.at_rest && next_rung_ == 0)
    ladder_ = session_->RefineLadder(plan.settings, service_->options.refine_min_still_ms);
  const bool rung = plan.at_rest && next_rung_ < ladder_.size();
  std::atomic<bool> moved{false};
  auto frame = session_->Render({.settings = &plan.settings,
                                 .interactive = plan.interactive,
                                 .want_vertices = plan.want_vertices,
                                 .cancel = FrameCancel(plan.at_rest, events, version, &moved),
                                 .refine_step_multiple = rung ? ladder_[next_rung_] : 0.0});
  auto lock = Lock();
  render_scheduled_ = false;
  if (moved.load()) {
    // The move's frame follows (its event or change marks the stream
    // dirty), cast while moving however long the band in progress took.
    answer_move_ = true;
    return ScheduleLocked();
  }
  if (!frame.ok()) return FinishLocked(ToGrpcStatus(frame.status()));
  auto out = std::make_unique<v3::Frame>(*std::move(frame));
  out->mutable_timings()->set_queue_ms(queue_ms);
  out->mutable_timings()->set_total_ms(out->timings().total_ms() + queue_ms);
  if (options_.per_stream_sequence) out->set_last_sequence(plan.sequence);
  if (rung) out->set_refine_level(int32_t(next_rung_ + 1));
  last_interactive_ = out->interactive();
  DeliverLocked(std::move(out));
  if (dirty_) return ScheduleLocked();
  if (rung) {
    // The next rung, or the still, as soon as the pool allows.
    ++next_rung_;
    return StillCheckLocked();
  }
  if (last_interactive_) PostStillCheckLocked(StillCheckDelay());
}

CancelToken FrameStream::FrameCancel(bool at_rest, uint64_t events, uint64_t version,
                                     std::atomic<bool>* moved) {
  return CancelToken([this, at_rest, events, version, moved]() -> Status {
    if (finishing_.load(std::memory_order_relaxed)) {
      return absl::CancelledError("the stream ended");
    }
    if (at_rest && (events_received_.load(std::memory_order_relaxed) != events ||
                    session_->version() != version)) {
      moved->store(true);
      return absl::AbortedError("the client moved: the refinement is dropped");
    }
    return service_->WorkAllowed();
  });
}

bool FrameStream::ClientActiveLocked() const {
  if (!events_.empty() || applying_) return true;
  return last_event_at_ != std::chrono::steady_clock::time_point{} &&
         MsSince(last_event_at_) < service_->options.still_delay_ms;
}

std::chrono::milliseconds FrameStream::StillCheckDelay() const {
  return std::chrono::milliseconds(int64_t(service_->options.still_delay_ms) + 5);
}

void FrameStream::PostStillCheckLocked(std::chrono::milliseconds delay) {
  std::weak_ptr<FrameStream> weak = weak_from_this();
  service_->render_pool->PostAfter(delay, [weak] {
    if (auto self = weak.lock()) self->StillCheck();
  });
}

void FrameStream::StillCheck() {
  auto lock = Lock();
  StillCheckLocked();
}

void FrameStream::StillCheckLocked() {
  if (!last_interactive_ || render_scheduled_ || finish_) return;
  if (session_->RecentlyChanged() || ClientActiveLocked()) {
    // Events still coming: look again later.
    still_deferrals_ = 0;
    return PostStillCheckLocked(StillCheckDelay());
  }
  // Interactive work first: while other jobs wait for the render pool
  // (other streams' events and frames), the still (or a rung) waits a
  // little, at most kMaxStillDeferrals times, rather than hold the
  // renderer ahead of them.
  if (service_->render_pool->queued() > 0 && still_deferrals_ < kMaxStillDeferrals) {
    ++still_deferrals_;
    return PostStillCheckLocked(kStillDeferral);
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

// The frame pipeline of one Interact or Watch stream, shared by both
// reactors: events are applied and frames rendered on the worker pool, never
// in a gRPC callback; one write is in flight at a time and the next is
// chained from OnWriteDone; while a write is in flight the newest rendered
// frame waits in a single slot and replaces (supersedes, counted) any older
// one there, so a slow reader costs at most two frames of memory. At most one
// render per stream is queued or running: changes that arrive meanwhile mark
// the stream dirty and are folded into the next render. Frames are
// interactive (cheap) while the client interacts: this stream's events keep
// arriving, or the session changed (camera, grab, drag, ...: from any
// client) within still_delay_ms. Once both have been idle that long, and
// while no other job waits for the render pool (for at most
// kMaxStillDeferrals x kStillDeferral longer), the frame refines: the rungs
// of the session's RefineLadder (refine_ladder.h; Frame.refine_level 1, 2,
// ...), each as soon as the last is sent and the pool allows, then the
// still, full-quality frame, exactly as a still rendered directly. A frame
// at rest (rung or still) stops between its bands once the client moves
// again (an event on this stream, or the session changed): the rest of the
// ladder is dropped and the move's interactive frame goes next. Whether the
// client is active is judged by when events arrive, not when they are
// applied, so that under load the queue wait does not turn a moving
// client's frames into stills.
//
// Calls on the sink (StartWrite, StartRead, Finish) are decided under the
// stream's mutex but made after it is released: each decision is appended to
// an outbox, and whichever thread finds the outbox idle drains it in order
// (docs/THREADS.md). So no lock is held across a gRPC call, a reaction that
// gRPC runs inline from StartWrite cannot deadlock, and the calls keep the
// order in which they were decided (nothing after Finish).
//
// Lifetime: the pool's tasks hold the FrameStream (shared_ptr), never the
// reactor; the reactor calls Detach() from OnDone, after which the stream
// makes no call on it.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/support/status.h>

#include "server/service/service_context.h"
#include "server/service/session.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

// What a reactor lends its stream.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void WriteFrame(const v3::Frame* frame) = 0;        // StartWrite
  virtual void FinishStream(const grpc::Status& status) = 0;  // Finish, called once
  virtual void ReadNext() {}                                  // StartRead (Interact)
};

class FrameStream : public std::enable_shared_from_this<FrameStream> {
 public:
  struct Options {
    bool per_stream_sequence = false;  // Interact: frames echo this stream's events
    // Who watches and in which role: checked before every frame is written
    // (session_access.h), so that a revoked viewer gets no frame more and
    // the stream ends with PERMISSION_DENIED.
    std::string user;
    SessionRole role = SessionRole::kViewer;
  };
  static std::shared_ptr<FrameStream> Create(ServiceContext* service,
                                             std::shared_ptr<Session> session,
                                             StreamSettings settings, FrameSink* sink,
                                             const Options& options);

  // Watches the session and asks for the first frame.
  void Attach();
  // Queues `event` for the pool, which applies queued events in order; a
  // camera or drag event replaces a queued one of the same kind right before
  // it (the newest wins for input too, so a slow scene never builds a
  // backlog). An invalid event finishes the stream with its status; more
  // than kMaxQueuedEvents waiting finishes it with RESOURCE_EXHAUSTED.
  void EnqueueEvent(const v3::ClientEvent& event);
  static constexpr size_t kMaxQueuedEvents = 256;
  // Starts the sink's next read unless the stream is finishing (no read may
  // start after Finish).
  void ReadNext();
  void RequestFrame();
  void OnWriteDone(bool ok);
  // Finishes after the write in flight (pending frames are dropped); the
  // first call wins.
  void Finish(const grpc::Status& status);
  // Finish once the queued events are applied (the client half-closed).
  void FinishAfterEvents(const grpc::Status& status);
  void Detach();

  uint64_t superseded() const;
  Session& session() { return *session_; }

 private:
  FrameStream(ServiceContext* service, std::shared_ptr<Session> session,
              StreamSettings settings, FrameSink* sink, const Options& options);
  void ApplyQueued();
  // Runs `task` on the render pool in this stream's lane (uncapped: an
  // admitted stream's work is never refused for room); false only once the
  // pool is shutting down.
  bool PostToPool(std::function<void()> task);
  void ScheduleLocked();
  // What the next render casts, decided under mutex_.
  struct FramePlan {
    StreamSettings settings;
    bool want_vertices = false;
    uint64_t sequence = 0;     // this stream's last event applied
    bool interactive = false;  // the client is moving
    bool at_rest = false;      // refinement: a rung or the still that ends it
  };
  FramePlan PlanLocked(bool session_changing);
  void RenderNow(std::chrono::steady_clock::time_point queued_at);
  // Polled by a render between its bands: a stream that ends meanwhile
  // (client gone, session closed, shutdown) stops its still after the band
  // in progress; so does a frame at_rest once the client moves again (an
  // event arrived after `events` were received, or the session's version
  // moved on from `version`), which sets *moved.
  CancelToken FrameCancel(bool at_rest, uint64_t events, uint64_t version,
                          std::atomic<bool>* moved);
  void DeliverLocked(std::unique_ptr<v3::Frame> frame);
  // Writes `frame`, or finishes the stream with PERMISSION_DENIED when the
  // user may no longer see the session.
  void WriteLocked(std::unique_ptr<v3::Frame> frame);
  // At rest (no event, no session change within still_delay_ms, no other
  // job waiting): the next rung or the still is scheduled; else checks
  // again later.
  void StillCheck();
  void StillCheckLocked();
  void PostStillCheckLocked(std::chrono::milliseconds delay);
  // --still-delay-ms and a little more: a check then finds a client idle
  // that long.
  std::chrono::milliseconds StillCheckDelay() const;
  // The client is interacting: events queued or being applied, or one
  // arrived within still_delay_ms.
  bool ClientActiveLocked() const;
  void FinishLocked(const grpc::Status& status);

  // A call on the sink, decided under mutex_ and made by Flush() without it.
  struct SinkCall {
    enum class Kind { kWrite, kRead, kFinish } kind;
    const v3::Frame* frame = nullptr;  // kWrite: owned by current_
    grpc::Status status;               // kFinish
  };
  // mutex_, released by its destructor, which then flushes the outbox.
  class Guard {
   public:
    explicit Guard(FrameStream* stream) : stream_(stream), lock_(stream->mutex_) {}
    ~Guard() {
      lock_.unlock();
      stream_->Flush();
    }
    Guard(const Guard&) = delete;
    Guard& operator=(const Guard&) = delete;

   private:
    FrameStream* stream_;
    std::unique_lock<std::mutex> lock_;
  };
  Guard Lock() { return Guard(this); }
  // Makes the outbox's calls in order, unless another thread (or this one,
  // further up the stack) is already doing so.
  void Flush();

  ServiceContext* service_;
  std::shared_ptr<Session> session_;
  Options options_;
  int64_t observer_token_ = 0;

  // Guards everything below; never held across a call on the sink.
  mutable std::mutex mutex_;
  FrameSink* sink_;  // null once detached
  std::deque<SinkCall> outbox_;
  bool flushing_ = false;
  StreamSettings settings_;
  bool want_vertices_ = false;
  uint64_t stream_sequence_ = 0;
  std::deque<v3::ClientEvent> events_;
  bool applying_ = false;
  std::optional<grpc::Status> finish_after_events_;
  // When this stream's client last sent an event (events arrive here before
  // they are applied: under load the queue wait must not turn a moving
  // client's frames into stills).
  std::chrono::steady_clock::time_point last_event_at_{};
  // Events EnqueueEvent received: a frame at rest polls it to stop when the
  // client moves.
  std::atomic<uint64_t> events_received_{0};
  // StillCheck found the client at rest: the next render refines.
  bool force_still_ = false;
  // The refinement's rungs (step multiples, Session::RefineLadder) and the
  // next one's index; the still comes after the last. Touched only by the
  // render task (at most one per stream).
  std::vector<double> ladder_;
  size_t next_rung_ = 0;
  // A frame at rest stopped because the client moved: the next is cast as
  // interactive.
  bool answer_move_ = false;
  // Still checks put off because other jobs waited for the pool.
  int still_deferrals_ = 0;
  static constexpr int kMaxStillDeferrals = 10;
  static constexpr std::chrono::milliseconds kStillDeferral{10};
  bool render_scheduled_ = false;
  bool dirty_ = false;
  bool last_interactive_ = false;
  bool write_in_flight_ = false;
  std::unique_ptr<v3::Frame> current_;  // being written
  std::unique_ptr<v3::Frame> pending_;  // the newest frame waiting for the write
  std::optional<grpc::Status> finish_;
  // finish_ is set: polled (without mutex_) by the render in progress, so
  // that a still for a stream that ended stops between its bands.
  std::atomic<bool> finishing_{false};
  bool finished_ = false;
  uint64_t frame_number_ = 0;
  uint64_t superseded_ = 0;
};

}  // namespace vpm::service

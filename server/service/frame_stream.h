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
// client) within still_delay_ms; a still, full-quality frame follows once
// both have been idle that long. Whether the client is active is judged by
// when events arrive, not when they are applied, so that under load the
// queue wait does not turn a moving client's frames into stills.
//
// Lifetime: the pool's tasks hold the FrameStream (shared_ptr), never the
// reactor; the reactor calls Detach() from OnDone, after which the stream
// makes no call on it.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>

#include <grpcpp/support/status.h>

#include "server/service/service_context.h"
#include "server/service/session.h"
#include "vpm/v2/vpm.pb.h"

namespace vpm::service {

// What a reactor lends its stream.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void WriteFrame(const v2::Frame* frame) = 0;        // StartWrite
  virtual void FinishStream(const grpc::Status& status) = 0;  // Finish, called once
  virtual void ReadNext() {}                                  // StartRead (Interact)
};

class FrameStream : public std::enable_shared_from_this<FrameStream> {
 public:
  struct Options {
    bool per_stream_sequence = false;  // Interact: frames echo this stream's events
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
  void EnqueueEvent(const v2::ClientEvent& event);
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
  void ScheduleLocked();
  void RenderNow(std::chrono::steady_clock::time_point queued_at);
  void DeliverLocked(std::unique_ptr<v2::Frame> frame);
  void WriteLocked(std::unique_ptr<v2::Frame> frame);
  void StillCheck();
  // The client is interacting: events queued or being applied, or one
  // arrived within still_delay_ms.
  bool ClientActiveLocked() const;
  void FinishLocked(const grpc::Status& status);

  ServiceContext* service_;
  std::shared_ptr<Session> session_;
  Options options_;
  int64_t observer_token_ = 0;

  // Recursive: gRPC may run a reaction inline from StartWrite or Finish.
  mutable std::recursive_mutex mutex_;
  FrameSink* sink_;  // null once detached
  StreamSettings settings_;
  bool want_vertices_ = false;
  uint64_t stream_sequence_ = 0;
  std::deque<v2::ClientEvent> events_;
  bool applying_ = false;
  std::optional<grpc::Status> finish_after_events_;
  // When this stream's client last sent an event (events arrive here before
  // they are applied: under load the queue wait must not turn a moving
  // client's frames into stills).
  std::chrono::steady_clock::time_point last_event_at_{};
  bool force_still_ = false;
  bool render_scheduled_ = false;
  bool dirty_ = false;
  bool last_interactive_ = false;
  bool write_in_flight_ = false;
  std::unique_ptr<v2::Frame> current_;  // being written
  std::unique_ptr<v2::Frame> pending_;  // the newest frame waiting for the write
  std::optional<grpc::Status> finish_;
  bool finished_ = false;
  uint64_t frame_number_ = 0;
  uint64_t superseded_ = 0;
};

}  // namespace vpm::service

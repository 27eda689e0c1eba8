// What the Interact and Watch reactors share around their FrameStream:
// write-done forwarding, cancellation, finishing exactly once (counted by
// method, status code and user), the admission checks of a new stream (the
// caller's user, draining, the per-user stream cap) and, when gRPC is done
// with the call, the release of everything the stream held (a test counts that every
// stream opened is closed).
//
// `Reactor` is grpc::ServerBidiReactor<In, v3::Frame> or
// grpc::ServerWriteReactor<v3::Frame>.
//
// Lifetime: a reactor owns itself (self_) from Make until OnDone, and every
// task it posts to a pool holds it too, so a task that runs after OnDone
// still finds it alive (and, finished, does nothing). What gRPC owns (the
// request, the context) may be gone while such a task runs: a client that
// cancels brings OnDone at any moment, so tasks read only the reactor's own
// copies (Interact's first message, Watch's request). Starting a stream
// (settings, transfer function, MIP window) is work for the render pool,
// never for the gRPC callback thread; a stream is never started once the
// call is finished (OnCancel may come first).
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream.h"
#include "server/service/grpc_status.h"
#include "server/service/service_context.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

template <typename Reactor>
class FrameStreamReactor : public Reactor,
                           public FrameSink,
                           public std::enable_shared_from_this<FrameStreamReactor<Reactor>> {
 public:
  // What gRPC gets from the service's handler: a reactor that owns itself.
  template <typename Derived, typename... Args>
  static Derived* Make(Args&&... args) {
    std::shared_ptr<Derived> reactor(new Derived(std::forward<Args>(args)...));
    reactor->self_ = reactor;
    static_cast<FrameStreamReactor*>(reactor.get())->Begin();
    return reactor.get();
  }

  void OnWriteDone(bool ok) override {
    if (auto s = stream()) s->OnWriteDone(ok);
  }
  void OnCancel() override {
    // Decided under the lock that StartStream takes: either the stream is
    // installed (and finishes the call), or the call is finished here and
    // no stream will ever be started on it. (Read and decided apart, a
    // stream started between the two would write to a finished call, which
    // then never completes and holds the server's shutdown.)
    std::shared_ptr<FrameStream> s;
    bool finish_here = false;
    {
      std::lock_guard lock(mutex_);
      s = stream_;
      if (!s && !finished_) finish_here = finished_ = true;
    }
    if (s) {
      s->Finish(grpc::Status::CANCELLED);
    } else if (finish_here) {
      FinishClaimed(grpc::Status::CANCELLED);
    }
  }
  void OnDone() override {
    if (auto s = stream()) {
      s->Detach();
      service_->streams->Unregister(registry_token_);
    }
    if (slot_held_) service_->streams->Release(user_);
    service_->metrics->StreamClosed();
    std::shared_ptr<FrameStreamReactor> last = std::move(self_);  // may free this
  }
  void WriteFrame(const v3::Frame* frame) override { this->StartWrite(frame); }
  void FinishStream(const grpc::Status& status) override {
    {
      std::lock_guard lock(mutex_);
      if (finished_) return;
      finished_ = true;
    }
    FinishClaimed(status);
  }

 protected:
  // The first reaction: admission, then the first read or the stream.
  virtual void Begin() = 0;

  // Makes the stream on the render pool: `make` builds it (settings,
  // session), `then` runs once it is attached. Nothing happens if the call
  // was finished meanwhile.
  void StartOnPool(std::function<Result<std::shared_ptr<FrameStream>>()> make,
                   std::function<void(FrameStream&)> then) {
    auto self = this->shared_from_this();
    const bool posted = service_->render_pool->Post(
        [self, make = std::move(make), then = std::move(then)] {
          {
            std::lock_guard lock(self->mutex_);
            if (self->finished_) return;
          }
          auto stream = make();
          if (!stream.ok()) return self->FinishStream(ToGrpcStatus(stream.status()));
          if (self->StartStream(*stream)) then(**stream);
        });
    if (!posted) FinishStream(grpc::Status(grpc::UNAVAILABLE, "the server is shutting down"));
  }

  // `method`: the RPC's name in metrics ("Interact", "Watch").
  FrameStreamReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                     const char* method)
      : service_(service), context_(context), method_(method) {
    service_->metrics->StreamOpened();
  }

  // The caller's user, draining, then a stream slot for this user (held
  // until OnDone). Runs in Begin, before any other reaction reads user_.
  Status Admit() {
    ASSIGN_OR_RETURN(user_, service_->auth->Authenticate(*context_));
    RETURN_IF_ERROR(service_->AdmitStream(user_, /*creates_state=*/false));
    slot_held_ = true;
    return absl::OkStatus();
  }

  // Installs the stream (OnCancel may run beside the reader), registers it
  // for shutdown and attaches it to its session; false (and nothing done)
  // when the call is already finished.
  bool StartStream(std::shared_ptr<FrameStream> stream) {
    {
      std::lock_guard lock(mutex_);
      if (finished_) return false;
      stream_ = stream;
      registry_token_ = service_->streams->Register(stream, user_, stream->session().id());
    }
    stream->Attach();
    return true;
  }

  // Counts and finishes the call; the caller has set finished_.
  void FinishClaimed(const grpc::Status& status) {
    service_->metrics->Request(method_, StatusCodeName(status.error_code()), user_);
    this->Finish(status);
  }

  std::shared_ptr<FrameStream> stream() const {
    std::lock_guard lock(mutex_);
    return stream_;
  }

  // The caller, once Admit succeeded (empty before).
  const std::string& user() const { return user_; }

  ServiceContext* const service_;
  grpc::CallbackServerContext* const context_;  // valid until OnDone

 private:
  std::string user_;
  const char* const method_;
  bool slot_held_ = false;
  int64_t registry_token_ = 0;
  std::shared_ptr<FrameStreamReactor> self_;  // from Make until OnDone
  mutable std::mutex mutex_;  // stream_, registry_token_ and finished_
  std::shared_ptr<FrameStream> stream_;
  bool finished_ = false;
};

}  // namespace vpm::service

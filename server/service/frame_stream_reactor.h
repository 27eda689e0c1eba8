// What the Interact and Watch reactors share around their FrameStream:
// write-done forwarding, cancellation, finishing exactly once (counted by
// method, status code and user), the admission checks of a new stream (the
// caller's user, draining, the per-user stream cap) and, when gRPC is done
// with the call,
// the release of everything the stream held (a test counts that every
// stream opened is closed).
//
// `Reactor` is grpc::ServerBidiReactor<In, v2::Frame> or
// grpc::ServerWriteReactor<v2::Frame>.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream.h"
#include "server/service/grpc_status.h"
#include "server/service/service_context.h"
#include "vpm/v2/vpm.pb.h"

namespace vpm::service {

template <typename Reactor>
class FrameStreamReactor : public Reactor, public FrameSink {
 public:
  void OnWriteDone(bool ok) override {
    if (auto s = stream()) s->OnWriteDone(ok);
  }
  void OnCancel() override {
    if (auto s = stream()) {
      s->Finish(grpc::Status::CANCELLED);
    } else {
      FinishStream(grpc::Status::CANCELLED);
    }
  }
  void OnDone() override {
    if (auto s = stream()) {
      s->Detach();
      service_->streams->Unregister(registry_token_);
    }
    if (slot_held_) service_->streams->Release(user_);
    service_->metrics->StreamClosed();
    delete this;
  }
  void WriteFrame(const v2::Frame* frame) override { this->StartWrite(frame); }
  void FinishStream(const grpc::Status& status) override {
    {
      std::lock_guard lock(mutex_);
      if (finished_) return;
      finished_ = true;
    }
    service_->metrics->Request(method_, StatusCodeName(status.error_code()), user_);
    this->Finish(status);
  }

 protected:
  // `method`: the RPC's name in metrics ("Interact", "Watch").
  FrameStreamReactor(ServiceContext* service, grpc::CallbackServerContext* /*context*/,
                     const char* method)
      : service_(service), method_(method) {
    service_->metrics->StreamOpened();
  }

  // The caller's user, draining, then a stream slot for this user (held
  // until OnDone).
  Status Admit(const grpc::CallbackServerContext& context) {
    ASSIGN_OR_RETURN(user_, service_->auth->Authenticate(context));
    if (service_->draining) return absl::UnavailableError("the server is shutting down");
    RETURN_IF_ERROR(service_->streams->Acquire(user_));
    slot_held_ = true;
    return absl::OkStatus();
  }

  // Installs the stream (OnCancel may run beside the reader), registers it
  // for shutdown and attaches it to its session.
  void StartStream(std::shared_ptr<FrameStream> stream) {
    {
      std::lock_guard lock(mutex_);
      stream_ = stream;
    }
    registry_token_ = service_->streams->Register(stream);
    stream->Attach();
  }

  std::shared_ptr<FrameStream> stream() const {
    std::lock_guard lock(mutex_);
    return stream_;
  }

  // The caller, once Admit succeeded (empty before).
  const std::string& user() const { return user_; }

  ServiceContext* const service_;

 private:
  std::string user_;
  const char* const method_;
  bool slot_held_ = false;
  int64_t registry_token_ = 0;
  mutable std::mutex mutex_;  // stream_ and finished_
  std::shared_ptr<FrameStream> stream_;
  bool finished_ = false;
};

}  // namespace vpm::service

#include "server/service/interact_reactor.h"

#include "server/service/grpc_status.h"

namespace vpm::service {

InteractReactor::InteractReactor(ServiceContext* service, grpc::CallbackServerContext* context)
    : service_(service), peer_(context->peer()) {
  service_->metrics->StreamOpened();
  if (Status auth = service_->auth->Check(*context); !auth.ok()) {
    FinishEarly(ToGrpcStatus(auth));
    return;
  }
  if (service_->draining) {
    FinishEarly(grpc::Status(grpc::UNAVAILABLE, "the server is shutting down"));
    return;
  }
  if (Status slot = service_->streams->Acquire(peer_); !slot.ok()) {
    FinishEarly(ToGrpcStatus(slot));
    return;
  }
  slot_held_ = true;
  StartRead(&request_);
}

void InteractReactor::OnReadDone(bool ok) {
  if (!ok) {
    // Half-close (or a broken stream): finish after the write in flight.
    if (stream_) {
      stream_->FinishAfterEvents(grpc::Status::OK);
    } else {
      FinishEarly(grpc::Status::OK);
    }
    return;
  }
  if (!stream_) {
    Start(request_);
    return;
  }
  if (!request_.session_id().empty() && request_.session_id() != stream_->session().id()) {
    stream_->Finish(grpc::Status(grpc::INVALID_ARGUMENT,
                                 "session_id: a stream stays on the session it opened"));
    return;
  }
  stream_->EnqueueEvent(request_.event());
  stream_->ReadNext();
}

void InteractReactor::Start(const v1::InteractRequest& first) {
  if (first.session_id().empty()) {
    FinishEarly(grpc::Status(grpc::INVALID_ARGUMENT,
                             "session_id: required on the first message of Interact"));
    return;
  }
  auto session = service_->sessions->Get(first.session_id());
  if (!session.ok()) {
    FinishEarly(ToGrpcStatus(session.status()));
    return;
  }
  // Settings on the first event shape the first frame too.
  auto settings = ToStreamSettings(
      first.event().has_settings() ? first.event().settings() : v1::RenderSettings(),
      (*session)->volume().volume, service_->options.max_frame_side);
  if (!settings.ok()) {
    FinishEarly(ToGrpcStatus(settings.status()));
    return;
  }
  {
    std::lock_guard lock(stream_mutex_);
    stream_ = FrameStream::Create(service_, *session, *std::move(settings), this,
                                  {.per_stream_sequence = true});
  }
  registry_token_ = service_->streams->Register(stream_);
  stream_->Attach();
  if (first.has_event()) stream_->EnqueueEvent(first.event());
  stream_->ReadNext();
}

void InteractReactor::OnWriteDone(bool ok) {
  if (stream_) stream_->OnWriteDone(ok);
}

void InteractReactor::OnCancel() {
  std::shared_ptr<FrameStream> stream;
  {
    std::lock_guard lock(stream_mutex_);
    stream = stream_;
  }
  if (stream) {
    stream->Finish(grpc::Status::CANCELLED);
  } else {
    FinishEarly(grpc::Status::CANCELLED);
  }
}

void InteractReactor::FinishStream(const grpc::Status& status) {
  {
    std::lock_guard lock(finish_mutex_);
    if (finished_) return;
    finished_ = true;
  }
  service_->metrics->Request("Interact", StatusCodeName(status.error_code()));
  Finish(status);
}

void InteractReactor::FinishEarly(const grpc::Status& status) { FinishStream(status); }

void InteractReactor::OnDone() {
  if (stream_) {
    stream_->Detach();
    service_->streams->Unregister(registry_token_);
  }
  if (slot_held_) service_->streams->Release(peer_);
  service_->metrics->StreamClosed();
  delete this;
}

}  // namespace vpm::service

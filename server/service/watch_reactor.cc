#include "server/service/watch_reactor.h"

#include "server/service/grpc_status.h"

namespace vpm::service {

WatchReactor::WatchReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                           const v1::WatchRequest& request)
    : service_(service), peer_(context->peer()) {
  service_->metrics->StreamOpened();
  auto start = [&]() -> Status {
    RETURN_IF_ERROR(service_->auth->Check(*context));
    if (service_->draining) return absl::UnavailableError("the server is shutting down");
    if (request.session_id().empty()) {
      return absl::InvalidArgumentError("session_id: required");
    }
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request.session_id()));
    ASSIGN_OR_RETURN(StreamSettings settings,
                     ToStreamSettings(request.settings(), session->volume().volume,
                                      service_->options.max_frame_side));
    RETURN_IF_ERROR(service_->streams->Acquire(peer_));
    slot_held_ = true;
    stream_ = FrameStream::Create(service_, session, std::move(settings), this, {});
    return absl::OkStatus();
  };
  if (Status s = start(); !s.ok()) {
    FinishStream(ToGrpcStatus(s));
    return;
  }
  registry_token_ = service_->streams->Register(stream_);
  stream_->Attach();
}

void WatchReactor::OnWriteDone(bool ok) {
  if (stream_) stream_->OnWriteDone(ok);
}

void WatchReactor::OnCancel() {
  if (stream_) {
    stream_->Finish(grpc::Status::CANCELLED);
  } else {
    FinishStream(grpc::Status::CANCELLED);
  }
}

void WatchReactor::FinishStream(const grpc::Status& status) {
  {
    std::lock_guard lock(finish_mutex_);
    if (finished_) return;
    finished_ = true;
  }
  service_->metrics->Request("Watch", StatusCodeName(status.error_code()));
  Finish(status);
}

void WatchReactor::OnDone() {
  if (stream_) {
    stream_->Detach();
    service_->streams->Unregister(registry_token_);
  }
  if (slot_held_) service_->streams->Release(peer_);
  service_->metrics->StreamClosed();
  delete this;
}

}  // namespace vpm::service

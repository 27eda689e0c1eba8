#include "server/service/interact_reactor.h"

#include "server/service/grpc_status.h"
#include "server/service/request_limits.h"

namespace vpm::service {

InteractReactor::InteractReactor(ServiceContext* service, grpc::CallbackServerContext* context)
    : FrameStreamReactor(service, context, "Interact") {}

void InteractReactor::Begin() {
  if (Status admitted = Admit(); !admitted.ok()) {
    FinishStream(ToGrpcStatus(admitted));
    return;
  }
  StartRead(&request_);
}

void InteractReactor::OnReadDone(bool ok) {
  const std::shared_ptr<FrameStream> current = stream();
  if (!ok) {
    // Half-close (or a broken stream): finish after the write in flight.
    if (current) {
      current->FinishAfterEvents(grpc::Status::OK);
    } else {
      FinishStream(grpc::Status::OK);
    }
    return;
  }
  if (Status limits = CheckRequestLimits(request_); !limits.ok()) {
    if (current) {
      current->Finish(ToGrpcStatus(limits));
    } else {
      FinishStream(ToGrpcStatus(limits));
    }
    return;
  }
  if (!current) {
    Start(request_);
    return;
  }
  if (!request_.session_id().empty() && request_.session_id() != current->session().id()) {
    current->Finish(grpc::Status(grpc::INVALID_ARGUMENT,
                                 "session_id: a stream stays on the session it opened"));
    return;
  }
  current->EnqueueEvent(request_.event());
  current->ReadNext();
}

void InteractReactor::Start(const v3::InteractRequest& first) {
  if (first.session_id().empty()) {
    FinishStream(grpc::Status(grpc::INVALID_ARGUMENT,
                              "session_id: required on the first message of Interact"));
    return;
  }
  // The next read starts only once the stream exists, so `first` is a copy
  // that the pool task owns.
  auto make = [this, first]() -> Result<std::shared_ptr<FrameStream>> {
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(first.session_id(), user(), SessionRole::kOwner));
    // Settings on the first event shape the first frame too.
    ASSIGN_OR_RETURN(StreamSettings settings,
                     ToStreamSettings(first.event().has_settings() ? first.event().settings()
                                                                   : v3::RenderSettings(),
                                      session->volume().volume, service_->options.max_frame_side));
    return FrameStream::Create(service_, session, std::move(settings), this,
                               {.per_stream_sequence = true,
                                .user = user(),
                                .role = SessionRole::kOwner});
  };
  StartOnPool(std::move(make), [first](FrameStream& stream) {
    if (first.has_event()) stream.EnqueueEvent(first.event());
    stream.ReadNext();
  });
}

}  // namespace vpm::service

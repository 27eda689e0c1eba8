#include "server/service/watch_reactor.h"

#include "server/service/grpc_status.h"
#include "server/service/request_limits.h"

namespace vpm::service {

WatchReactor::WatchReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                           const v3::WatchRequest& request)
    : FrameStreamReactor(service, context, "Watch"), request_(request) {}

void WatchReactor::Begin() {
  if (Status admitted = Admit(); !admitted.ok()) {
    FinishStream(ToGrpcStatus(admitted));
    return;
  }
  if (Status limits = CheckRequestLimits(request_); !limits.ok()) {
    FinishStream(ToGrpcStatus(limits));
    return;
  }
  if (request_.session_id().empty()) {
    FinishStream(grpc::Status(grpc::INVALID_ARGUMENT, "session_id: required"));
    return;
  }
  StartOnPool(
      [this]() -> Result<std::shared_ptr<FrameStream>> {
        ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                         service_->sessions->Get(request_.session_id(), user(),
                                                 SessionRole::kViewer));
        ASSIGN_OR_RETURN(StreamSettings settings,
                         ToStreamSettings(request_.settings(), session->volume().volume,
                                          service_->options.max_frame_side));
        return FrameStream::Create(service_, session, std::move(settings), this,
                                   {.user = user(), .role = SessionRole::kViewer});
      },
      [](FrameStream&) {});
}

}  // namespace vpm::service

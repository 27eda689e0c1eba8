#include "server/service/watch_reactor.h"

#include "server/service/grpc_status.h"

namespace vpm::service {

WatchReactor::WatchReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                           const v2::WatchRequest& request)
    : FrameStreamReactor(service, context, "Watch") {
  auto start = [&]() -> Result<std::shared_ptr<FrameStream>> {
    RETURN_IF_ERROR(Admit(*context));
    if (request.session_id().empty()) {
      return absl::InvalidArgumentError("session_id: required");
    }
    ASSIGN_OR_RETURN(std::shared_ptr<Session> session,
                     service_->sessions->Get(request.session_id(), user(), SessionRole::kViewer));
    ASSIGN_OR_RETURN(StreamSettings settings,
                     ToStreamSettings(request.settings(), session->volume().volume,
                                      service_->options.max_frame_side));
    return FrameStream::Create(service_, session, std::move(settings), this, {});
  };
  auto stream = start();
  if (!stream.ok()) {
    FinishStream(ToGrpcStatus(stream.status()));
    return;
  }
  StartStream(*std::move(stream));
}

}  // namespace vpm::service

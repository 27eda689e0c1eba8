// Interact: events in, frames out, on one bidirectional stream. The first
// message names the session; events are read continuously and queued on the
// FrameStream (frame_stream.h), which applies them in order on the worker
// pool (camera and drag events coalesce) and streams the frames. Finish is called once:
// OK when the client half-closes, the event's status when one is invalid,
// CANCELLED when the client goes away, UNAVAILABLE on shutdown.
#pragma once

#include <memory>

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream_reactor.h"

namespace vpm::service {

class InteractReactor
    : public FrameStreamReactor<grpc::ServerBidiReactor<v3::InteractRequest, v3::Frame>> {
 public:
  InteractReactor(ServiceContext* service, grpc::CallbackServerContext* context);

  void OnReadDone(bool ok) override;
  void ReadNext() override { StartRead(&request_); }

 private:
  void Begin() override;
  void Start(const v3::InteractRequest& first);

  v3::InteractRequest request_;
};

}  // namespace vpm::service

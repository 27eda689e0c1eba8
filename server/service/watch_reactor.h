// Watch: frames of a session for clients without bidirectional streams
// (browsers); events reach the session through Manipulate and SetCamera
// (from this or any other client). Frames flow through a FrameStream, so the
// newest frame wins for a slow reader. Finish once: CANCELLED when the client
// goes away, FAILED_PRECONDITION when the session closes, UNAVAILABLE on
// shutdown.
#pragma once

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream_reactor.h"

namespace vpm::service {

class WatchReactor : public FrameStreamReactor<grpc::ServerWriteReactor<v3::Frame>> {
 public:
  WatchReactor(ServiceContext* service, grpc::CallbackServerContext* context,
               const v3::WatchRequest& request);

 private:
  void Begin() override;

  // A copy: gRPC frees its request once the call is done (OnDone), and the
  // render pool may still be making the stream from it then.
  const v3::WatchRequest request_;
};

}  // namespace vpm::service

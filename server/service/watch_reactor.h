// Watch: frames of a session for clients without bidirectional streams
// (browsers); events reach the session through Manipulate and SetCamera
// (from this or any other client). Frames flow through a FrameStream, so the
// newest frame wins for a slow reader. Finish once: CANCELLED when the client
// goes away, FAILED_PRECONDITION when the session closes, UNAVAILABLE on
// shutdown.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream.h"
#include "server/service/service_context.h"
#include "vpm/v1/vpm.pb.h"

namespace vpm::service {

class WatchReactor : public grpc::ServerWriteReactor<v1::Frame>, public FrameSink {
 public:
  WatchReactor(ServiceContext* service, grpc::CallbackServerContext* context,
               const v1::WatchRequest& request);

  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  void WriteFrame(const v1::Frame* frame) override { StartWrite(frame); }
  void FinishStream(const grpc::Status& status) override;

 private:
  ServiceContext* service_;
  std::string peer_;
  bool slot_held_ = false;
  std::shared_ptr<FrameStream> stream_;
  int64_t registry_token_ = 0;
  std::mutex finish_mutex_;
  bool finished_ = false;
};

}  // namespace vpm::service

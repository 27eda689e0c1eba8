// Interact: events in, frames out, on one bidirectional stream. The first
// message names the session; events are read continuously and queued on the
// FrameStream (frame_stream.h), which applies them in order on the worker
// pool (camera and drag events coalesce) and streams the frames. Finish is called once:
// OK when the client half-closes, the event's status when one is invalid,
// CANCELLED when the client goes away, UNAVAILABLE on shutdown.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/service/frame_stream.h"
#include "server/service/service_context.h"
#include "vpm/v1/vpm.pb.h"

namespace vpm::service {

class InteractReactor : public grpc::ServerBidiReactor<v1::InteractRequest, v1::Frame>,
                        public FrameSink {
 public:
  InteractReactor(ServiceContext* service, grpc::CallbackServerContext* context);

  void OnReadDone(bool ok) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  void WriteFrame(const v1::Frame* frame) override { StartWrite(frame); }
  void FinishStream(const grpc::Status& status) override;
  void ReadNext() override { StartRead(&request_); }

 private:
  void Start(const v1::InteractRequest& first);
  void FinishEarly(const grpc::Status& status);

  ServiceContext* service_;
  std::string peer_;
  bool slot_held_ = false;
  v1::InteractRequest request_;
  std::mutex stream_mutex_;  // OnCancel may run beside OnReadDone
  std::shared_ptr<FrameStream> stream_;
  int64_t registry_token_ = 0;
  std::mutex finish_mutex_;
  bool finished_ = false;
};

}  // namespace vpm::service

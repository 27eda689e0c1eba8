// ExportDicom's stream: the export (export_dicom.h) runs on the request
// pool and emits messages; this reactor writes them one at a time, holding
// the exporter back while more than kMaxQueuedBytes wait (a series of
// large slices is never all in the queue), and finishes the call once with
// the export's status.
//
// Lifetime: the reactor owns itself (self_) from Make until OnDone; the
// pool job holds it too. After the call is finished (cancelled, failed)
// emit returns Cancelled, so the export stops at its next message.
#pragma once

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <string>

#include <grpcpp/grpcpp.h>

#include "server/service/service_context.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::service {

class ExportDicomReactor : public grpc::ServerWriteReactor<v3::ExportDicomPart>,
                           public std::enable_shared_from_this<ExportDicomReactor> {
 public:
  static constexpr int64_t kMaxQueuedBytes = int64_t{16} << 20;

  static ExportDicomReactor* Make(ServiceContext* service, grpc::CallbackServerContext* context,
                                  const v3::ExportDicomRequest& request);

  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

 private:
  ExportDicomReactor(ServiceContext* service, grpc::CallbackServerContext* context,
                     const v3::ExportDicomRequest& request);
  void Begin();
  void Run();  // on the request pool
  Status Emit(v3::ExportDicomPart part);
  // Writes the next queued message unless one is being written (mutex_ held).
  void WriteNextLocked();
  // The export ended: finish once the queue has drained.
  void EndWith(const Status& status);
  void FinishLocked(const Status& status);

  ServiceContext* service_;
  grpc::CallbackServerContext* context_;
  const v3::ExportDicomRequest request_;
  std::string user_;
  bool slot_held_ = false;
  std::shared_ptr<ExportDicomReactor> self_;

  std::mutex mutex_;
  std::condition_variable drained_;
  std::deque<v3::ExportDicomPart> queue_;
  v3::ExportDicomPart writing_;  // the message gRPC is writing
  bool write_in_flight_ = false;
  int64_t queued_bytes_ = 0;
  bool ended_ = false;     // the export returned
  Status end_status_;
  bool finished_ = false;  // Finish was called
};

}  // namespace vpm::service

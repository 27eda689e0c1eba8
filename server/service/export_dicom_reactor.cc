#include "server/service/export_dicom_reactor.h"

#include "server/service/export_dicom.h"
#include "server/service/grpc_status.h"
#include "server/service/request_limits.h"

namespace vpm::service {

ExportDicomReactor* ExportDicomReactor::Make(ServiceContext* service,
                                             grpc::CallbackServerContext* context,
                                             const v3::ExportDicomRequest& request) {
  std::shared_ptr<ExportDicomReactor> reactor(new ExportDicomReactor(service, context, request));
  reactor->self_ = reactor;
  reactor->Begin();
  return reactor.get();
}

ExportDicomReactor::ExportDicomReactor(ServiceContext* service,
                                       grpc::CallbackServerContext* context,
                                       const v3::ExportDicomRequest& request)
    : service_(service), context_(context), request_(request) {
  service_->metrics->StreamOpened();
}

void ExportDicomReactor::Begin() {
  Result<std::string> user = service_->auth->Authenticate(*context_);
  Status admitted = user.status();
  if (admitted.ok()) user_ = *std::move(user);
  if (admitted.ok()) admitted = CheckRequestLimits(request_);
  if (admitted.ok()) admitted = service_->AdmitStream(user_, /*creates_state=*/true);
  if (!admitted.ok()) {
    std::lock_guard lock(mutex_);
    FinishLocked(admitted);
    return;
  }
  slot_held_ = true;
  auto self = shared_from_this();
  const Status queued = service_->request_pool->Submit(Job{
      .lane = user_,
      .run = [self] { self->Run(); },
      .drop = [self] { self->EndWith(absl::UnavailableError("the server shut down first")); }});
  if (!queued.ok()) EndWith(queued);
}

void ExportDicomReactor::Run() {
  // The context is read under the lock, before Finish: OnDone (after
  // which it is gone) cannot come meanwhile.
  const CancelToken cancel([this]() -> Status {
    {
      std::lock_guard lock(mutex_);
      if (finished_) return absl::CancelledError("the call was finished");
      if (context_->IsCancelled()) return absl::CancelledError("the call was cancelled");
    }
    return service_->WorkAllowed();
  });
  const Status status = RunDicomExport(
      service_, user_, request_, [this](v3::ExportDicomPart part) { return Emit(std::move(part)); },
      cancel);
  EndWith(status);
}

Status ExportDicomReactor::Emit(v3::ExportDicomPart part) {
  std::unique_lock lock(mutex_);
  // Back-pressure: the exporter waits while the client reads.
  drained_.wait(lock, [this] { return finished_ || queued_bytes_ < kMaxQueuedBytes; });
  if (finished_) return absl::CancelledError("the call was finished");
  queued_bytes_ += int64_t(part.ByteSizeLong());
  queue_.push_back(std::move(part));
  WriteNextLocked();
  return absl::OkStatus();
}

void ExportDicomReactor::WriteNextLocked() {
  if (write_in_flight_ || finished_) return;
  if (queue_.empty()) {
    if (ended_) FinishLocked(end_status_);
    return;
  }
  writing_ = std::move(queue_.front());
  queue_.pop_front();
  write_in_flight_ = true;
  StartWrite(&writing_);
}

void ExportDicomReactor::OnWriteDone(bool ok) {
  std::lock_guard lock(mutex_);
  write_in_flight_ = false;
  queued_bytes_ -= int64_t(writing_.ByteSizeLong());
  drained_.notify_all();
  if (!ok) {
    FinishLocked(absl::CancelledError("the client stopped reading"));
    return;
  }
  WriteNextLocked();
}

void ExportDicomReactor::EndWith(const Status& status) {
  std::lock_guard lock(mutex_);
  ended_ = true;
  end_status_ = status;
  if (!status.ok()) {
    queue_.clear();  // an error ends the stream without the rest
    queued_bytes_ = write_in_flight_ ? int64_t(writing_.ByteSizeLong()) : 0;
  }
  WriteNextLocked();
}

void ExportDicomReactor::FinishLocked(const Status& status) {
  if (finished_) return;
  finished_ = true;
  drained_.notify_all();
  const grpc::Status g = ToGrpcStatus(status);
  service_->metrics->Request("ExportDicom", StatusCodeName(g.error_code()), user_);
  Finish(g);
}

void ExportDicomReactor::OnCancel() {
  std::lock_guard lock(mutex_);
  FinishLocked(absl::CancelledError("the client cancelled"));
}

void ExportDicomReactor::OnDone() {
  if (slot_held_) service_->streams->Release(user_);
  service_->metrics->StreamClosed();
  std::shared_ptr<ExportDicomReactor> last = std::move(self_);  // may free this
}

}  // namespace vpm::service

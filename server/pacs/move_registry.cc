#include "server/pacs/move_registry.h"

#include <chrono>
#include <cstdio>

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

std::string MoveKey(const std::string& series_uid, const std::string& peer_ae) {
  return series_uid + " " + peer_ae;
}

}  // namespace

Status MoveRegistry::Sink::Keep(const fs::path& file, int64_t bytes) {
  std::lock_guard lock(mutex_);
  RETURN_IF_ERROR(failure_);
  if (bytes_ + bytes > max_bytes_) {
    failure_ = absl::ResourceExhaustedError(
        StrCat("the series is over ", max_bytes_, " bytes (--pacs-cache-bytes)"));
    changed_.notify_all();
    return failure_;
  }
  char name[32];
  std::snprintf(name, sizeof name, "%06lld.dcm", static_cast<long long>(instances_ + 1));
  std::error_code error;
  fs::rename(file, folder_ / name, error);
  if (error) {
    error.clear();
    fs::copy_file(file, folder_ / name, error);
    if (!error) fs::remove(file, error);
  }
  if (error) {
    failure_ = absl::InternalError("cannot keep an instance of a C-MOVE");
    changed_.notify_all();
    return failure_;
  }
  ++instances_;
  bytes_ += bytes;
  changed_.notify_all();
  return absl::OkStatus();
}

void MoveRegistry::Sink::Fail(const Status& status) {
  std::lock_guard lock(mutex_);
  if (failure_.ok()) failure_ = status;
  changed_.notify_all();
}

MoveRegistry::Expectation::~Expectation() {
  std::lock_guard lock(registry_->mutex_);
  registry_->moves_.erase(key_);
}

Status MoveRegistry::Expectation::WaitFor(int64_t instances, const CancelToken& cancel,
                                          double timeout_s) const {
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(timeout_s));
  std::unique_lock lock(sink_->mutex_);
  while (sink_->instances_ < instances && sink_->failure_.ok()) {
    lock.unlock();
    RETURN_IF_ERROR(cancel.Check());
    lock.lock();
    if (std::chrono::steady_clock::now() >= deadline) {
      return absl::DeadlineExceededError(
          StrCat("the PACS reported ", instances, " instances sent by C-MOVE, vpm's listener got ",
                 sink_->instances_));
    }
    sink_->changed_.wait_for(lock, std::chrono::milliseconds(50));
  }
  return sink_->failure_;
}

int64_t MoveRegistry::Expectation::instances() const {
  std::lock_guard lock(sink_->mutex_);
  return sink_->instances_;
}

int64_t MoveRegistry::Expectation::bytes() const {
  std::lock_guard lock(sink_->mutex_);
  return sink_->bytes_;
}

Status MoveRegistry::Expectation::failure() const {
  std::lock_guard lock(sink_->mutex_);
  return sink_->failure_;
}

Result<std::unique_ptr<MoveRegistry::Expectation>> MoveRegistry::Expect(
    const std::string& series_uid, const std::string& peer_ae, const std::string& originator_ae,
    const fs::path& folder, int64_t max_bytes) {
  auto sink = std::make_shared<Sink>();
  sink->folder_ = folder;
  sink->max_bytes_ = max_bytes;
  const std::string key = MoveKey(series_uid, peer_ae);
  std::lock_guard lock(mutex_);
  if (!moves_.emplace(key, Entry{originator_ae, sink}).second) {
    return absl::FailedPreconditionError(
        StrCat("a C-MOVE of series ", series_uid, " from ", peer_ae, " is under way already"));
  }
  auto expectation = std::unique_ptr<Expectation>(new Expectation());
  expectation->registry_ = this;
  expectation->key_ = key;
  expectation->sink_ = std::move(sink);
  return expectation;
}

std::shared_ptr<MoveRegistry::Sink> MoveRegistry::Route(const std::string& series_uid,
                                                        const std::string& calling_ae,
                                                        const std::string& originator_ae) const {
  std::lock_guard lock(mutex_);
  auto it = moves_.find(MoveKey(series_uid, calling_ae));
  if (it == moves_.end()) return nullptr;
  if (!originator_ae.empty() && originator_ae != it->second.originator_ae) return nullptr;
  return it->second.sink;
}

}  // namespace vpm::pacs

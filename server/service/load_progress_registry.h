// The progress of the loads clients asked to follow (LoadVolumeRequest.
// progress_id), for GetLoadProgress polls: an entry per id, made when the
// load is queued, updated by the reader and the upload, kept for a while
// after the load ends so that the last poll sees "done" or "failed".
// Thread-safe; bounded (the oldest finished entries go first).
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/progress.h"
#include "server/common/status.h"

namespace vpm::service {

struct LoadProgressState {
  double fraction = 0.0;  // 0 to 1, never decreasing
  std::string stage;      // "queued", "reading", "uploading", "done", "failed"
  bool done = false;
  Status status;          // the load's error once done
};

class LoadProgressRegistry {
 public:
  struct Options {
    size_t max_entries = 1024;
    std::chrono::seconds keep_after_done{60};
  };
  explicit LoadProgressRegistry(Options options) : options_(options) {}
  LoadProgressRegistry() : LoadProgressRegistry(Options{}) {}

  // InvalidArgument unless `id` is 1..64 of [A-Za-z0-9_-].
  static Status CheckId(std::string_view id);
  // A new entry ("queued", 0); AlreadyExists while a load with this id runs;
  // ResourceExhausted when full of running loads.
  Status Start(const std::string& id);
  // Reports into the entry (monotone; ignored once done).
  ProgressFn Reporter(const std::string& id);
  // Ends the entry: fraction 1 and "done" on success, "failed" otherwise.
  void Finish(const std::string& id, const Status& status);
  // NotFound for an id never started or long finished.
  Result<LoadProgressState> Get(const std::string& id) const;

 private:
  struct Entry {
    LoadProgressState state;
    std::chrono::steady_clock::time_point finished_at{};
  };
  void EvictLocked();

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace vpm::service

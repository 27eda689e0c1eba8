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

  // Ids are each user's own: `user`'s id names nothing of another user's
  // loads (the same id of two users is two entries; another user's is
  // NotFound like a missing one).
  // InvalidArgument unless `id` is 1..64 of [A-Za-z0-9_-].
  static Status CheckId(std::string_view id);
  // A new entry ("queued", 0); AlreadyExists while a load of `user`'s with
  // this id runs; ResourceExhausted when full of running loads.
  Status Start(std::string_view user, const std::string& id);
  // Reports into the entry (monotone; ignored once done).
  ProgressFn Reporter(std::string_view user, const std::string& id);
  // Ends the entry: fraction 1 and "done" on success, "failed" otherwise.
  void Finish(std::string_view user, const std::string& id, const Status& status);
  // NotFound for an id `user` never started or long finished.
  Result<LoadProgressState> Get(std::string_view user, const std::string& id) const;

 private:
  struct Entry {
    LoadProgressState state;
    std::chrono::steady_clock::time_point finished_at{};
  };
  void EvictLocked();
  static std::string Key(std::string_view user, std::string_view id);

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace vpm::service

// A server-wide budget of bytes (e.g. uploads held in memory while they
// arrive): reserved before allocating, released when freed. Thread-safe.
#pragma once

#include <cstdint>
#include <mutex>
#include <string_view>

#include "server/common/status.h"

namespace vpm::service {

class ByteBudget {
 public:
  // `limit_bytes` <= 0: no limit.
  explicit ByteBudget(int64_t limit_bytes) : limit_(limit_bytes) {}

  // ResourceExhausted (naming `what`, the request and what is in use) when
  // `bytes` would pass the limit; nothing is reserved then.
  Status Reserve(int64_t bytes, std::string_view what) {
    std::lock_guard lock(mutex_);
    if (limit_ > 0 && bytes > limit_ - used_) {
      return absl::ResourceExhaustedError(StrCat(what, ": ", bytes, " bytes would pass the budget of ",
                                                 limit_, " bytes (", used_,
                                                 " in use by others); retry later"));
    }
    used_ += bytes;
    return absl::OkStatus();
  }
  void Release(int64_t bytes) {
    std::lock_guard lock(mutex_);
    used_ -= bytes;
  }
  int64_t used() const {
    std::lock_guard lock(mutex_);
    return used_;
  }

 private:
  const int64_t limit_;
  mutable std::mutex mutex_;
  int64_t used_ = 0;
};

}  // namespace vpm::service

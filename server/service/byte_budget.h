// A server-wide budget of bytes (e.g. uploads held in memory while they
// arrive), with a share per key (the user): reserved before allocating,
// released when freed. A reservation passes only if it fits both the total
// and its key's share, so one user at their share leaves the rest of the
// total to everyone else. Thread-safe.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::service {

class ByteBudget {
 public:
  // `limit_bytes`, `per_key_limit_bytes` <= 0: no limit.
  explicit ByteBudget(int64_t limit_bytes, int64_t per_key_limit_bytes = 0)
      : limit_(limit_bytes), per_key_limit_(per_key_limit_bytes) {}

  // ResourceExhausted (naming `what`, the request and what is in use) when
  // `bytes` would pass the total or `key`'s share; nothing is reserved then.
  Status Reserve(const std::string& key, int64_t bytes, std::string_view what) {
    std::lock_guard lock(mutex_);
    const int64_t mine = Used(key);
    if (per_key_limit_ > 0 && bytes > per_key_limit_ - mine) {
      return absl::ResourceExhaustedError(
          StrCat(what, ": ", bytes, " more bytes would pass your share of the budget, ",
                 per_key_limit_, " bytes (", mine, " in use by your uploads); retry later"));
    }
    if (limit_ > 0 && bytes > limit_ - used_) {
      return absl::ResourceExhaustedError(StrCat(what, ": ", bytes,
                                                 " more bytes would pass the budget of ", limit_,
                                                 " bytes (", used_, " in use); retry later"));
    }
    used_ += bytes;
    per_key_[key] += bytes;
    return absl::OkStatus();
  }
  void Release(const std::string& key, int64_t bytes) {
    std::lock_guard lock(mutex_);
    used_ -= bytes;
    auto it = per_key_.find(key);
    if (it != per_key_.end() && (it->second -= bytes) <= 0) per_key_.erase(it);
  }
  int64_t used() const {
    std::lock_guard lock(mutex_);
    return used_;
  }
  int64_t per_key_limit() const { return per_key_limit_; }

 private:
  int64_t Used(const std::string& key) const {
    auto it = per_key_.find(key);
    return it == per_key_.end() ? 0 : it->second;
  }

  const int64_t limit_;
  const int64_t per_key_limit_;
  mutable std::mutex mutex_;
  int64_t used_ = 0;
  std::map<std::string, int64_t> per_key_;
};

}  // namespace vpm::service

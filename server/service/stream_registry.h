// Streams per user (the caller's user name, token_auth.h: behind a gateway
// or a balancer every user shares one peer address, so a cap by address
// would be one cap for all) and every live frame stream, so that the
// per-user cap holds and shutdown can finish them all.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include <grpcpp/support/status.h>

#include "server/common/status.h"

namespace vpm::service {

class FrameStream;

class StreamRegistry {
 public:
  // on_change: metrics, a user's stream count after each change.
  explicit StreamRegistry(int64_t max_per_user,
                          std::function<void(const std::string& user, int64_t streams)> on_change =
                              nullptr)
      : max_per_user_(max_per_user), on_change_(std::move(on_change)) {}
  // ResourceExhausted past the per-user cap.
  Status Acquire(const std::string& user);
  void Release(const std::string& user);
  // A frame stream of `user` on session `session_id`, until Unregister.
  int64_t Register(std::weak_ptr<FrameStream> stream, std::string user, std::string session_id);
  void Unregister(int64_t token);
  // Finishes every registered stream with `status`.
  void FinishAll(const grpc::Status& status);
  // Finishes the streams on session `session_id` with `status`: those of
  // `user`, or every one when `user` is empty (the share revoked, the
  // session closed). Returns how many.
  int FinishSession(std::string_view session_id, std::string_view user,
                    const grpc::Status& status);
  int64_t open_streams() const;

 private:
  int64_t max_per_user_;
  std::function<void(const std::string& user, int64_t streams)> on_change_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> per_user_;
  struct Entry {
    std::weak_ptr<FrameStream> stream;
    std::string user;
    std::string session_id;
  };
  std::map<int64_t, Entry> streams_;
  int64_t next_token_ = 1;
};

}  // namespace vpm::service

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
  int64_t Register(std::weak_ptr<FrameStream> stream);
  void Unregister(int64_t token);
  // Finishes every registered stream with `status`.
  void FinishAll(const grpc::Status& status);
  int64_t open_streams() const;

 private:
  int64_t max_per_user_;
  std::function<void(const std::string& user, int64_t streams)> on_change_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> per_user_;
  std::map<int64_t, std::weak_ptr<FrameStream>> streams_;
  int64_t next_token_ = 1;
};

}  // namespace vpm::service

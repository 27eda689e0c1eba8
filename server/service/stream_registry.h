// Streams per client (peer address without the port) and every live frame
// stream, so that the per-client cap holds and shutdown can finish them all.
#pragma once

#include <cstdint>
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
  explicit StreamRegistry(int64_t max_per_client) : max_per_client_(max_per_client) {}
  // ResourceExhausted past the per-client cap.
  Status Acquire(const std::string& peer);
  void Release(const std::string& peer);
  int64_t Register(std::weak_ptr<FrameStream> stream);
  void Unregister(int64_t token);
  // Finishes every registered stream with `status`.
  void FinishAll(const grpc::Status& status);
  int64_t open_streams() const;

  static std::string ClientOf(const std::string& peer);

 private:
  int64_t max_per_client_;
  mutable std::mutex mutex_;
  std::map<std::string, int64_t> per_client_;
  std::map<int64_t, std::weak_ptr<FrameStream>> streams_;
  int64_t next_token_ = 1;
};

}  // namespace vpm::service

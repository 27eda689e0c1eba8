#include "server/service/stream_registry.h"

#include <vector>

#include "server/service/frame_stream.h"

namespace vpm::service {

std::string StreamRegistry::ClientOf(const std::string& peer) {
  const size_t colon = peer.rfind(':');
  return colon == std::string::npos ? peer : peer.substr(0, colon);
}

Status StreamRegistry::Acquire(const std::string& peer) {
  std::lock_guard lock(mutex_);
  int64_t& count = per_client_[ClientOf(peer)];
  if (max_per_client_ > 0 && count >= max_per_client_) {
    if (count == 0) per_client_.erase(ClientOf(peer));
    return absl::ResourceExhaustedError(
        StrCat("this client holds its maximum of ", max_per_client_, " streams"));
  }
  ++count;
  return absl::OkStatus();
}

void StreamRegistry::Release(const std::string& peer) {
  std::lock_guard lock(mutex_);
  auto it = per_client_.find(ClientOf(peer));
  if (it != per_client_.end() && --it->second <= 0) per_client_.erase(it);
}

int64_t StreamRegistry::Register(std::weak_ptr<FrameStream> stream) {
  std::lock_guard lock(mutex_);
  const int64_t token = next_token_++;
  streams_.emplace(token, std::move(stream));
  return token;
}

void StreamRegistry::Unregister(int64_t token) {
  std::lock_guard lock(mutex_);
  streams_.erase(token);
}

void StreamRegistry::FinishAll(const grpc::Status& status) {
  std::vector<std::shared_ptr<FrameStream>> live;
  {
    std::lock_guard lock(mutex_);
    for (auto& [token, weak] : streams_) {
      if (auto s = weak.lock()) live.push_back(std::move(s));
    }
  }
  for (auto& s : live) s->Finish(status);
}

int64_t StreamRegistry::open_streams() const {
  std::lock_guard lock(mutex_);
  return static_cast<int64_t>(streams_.size());
}

}  // namespace vpm::service

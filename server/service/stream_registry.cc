#include "server/service/stream_registry.h"

#include <vector>

#include "server/service/frame_stream.h"

namespace vpm::service {

Status StreamRegistry::Acquire(const std::string& user) {
  std::lock_guard lock(mutex_);
  int64_t& count = per_user_[user];
  if (max_per_user_ > 0 && count >= max_per_user_) {
    if (count == 0) per_user_.erase(user);
    return absl::ResourceExhaustedError(
        StrCat("user '", user, "' holds the maximum of ", max_per_user_,
               " Interact and Watch streams per user; end one first"));
  }
  ++count;
  if (on_change_) on_change_(user, count);
  return absl::OkStatus();
}

void StreamRegistry::Release(const std::string& user) {
  std::lock_guard lock(mutex_);
  auto it = per_user_.find(user);
  if (it == per_user_.end()) return;
  const int64_t left = --it->second;
  if (left <= 0) per_user_.erase(it);
  if (on_change_) on_change_(user, left > 0 ? left : 0);
}

int64_t StreamRegistry::Register(std::weak_ptr<FrameStream> stream, std::string user,
                                 std::string session_id) {
  std::lock_guard lock(mutex_);
  const int64_t token = next_token_++;
  streams_.emplace(token, Entry{std::move(stream), std::move(user), std::move(session_id)});
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
    for (auto& [token, entry] : streams_) {
      if (auto s = entry.stream.lock()) live.push_back(std::move(s));
    }
  }
  for (auto& s : live) s->Finish(status);
}

int StreamRegistry::FinishSession(std::string_view session_id, std::string_view user,
                                  const grpc::Status& status) {
  std::vector<std::shared_ptr<FrameStream>> affected;
  {
    std::lock_guard lock(mutex_);
    for (auto& [token, entry] : streams_) {
      if (entry.session_id != session_id || (!user.empty() && entry.user != user)) continue;
      if (auto s = entry.stream.lock()) affected.push_back(std::move(s));
    }
  }
  // Finished after the registry's lock is released (FrameStream::mutex_ is
  // taken before it, never after).
  for (auto& s : affected) s->Finish(status);
  return static_cast<int>(affected.size());
}

int64_t StreamRegistry::open_streams() const {
  std::lock_guard lock(mutex_);
  return static_cast<int64_t>(streams_.size());
}

}  // namespace vpm::service

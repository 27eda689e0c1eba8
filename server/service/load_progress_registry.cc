#include "server/service/load_progress_registry.h"

#include <algorithm>

namespace vpm::service {

Status LoadProgressRegistry::CheckId(std::string_view id) {
  const bool ok = !id.empty() && id.size() <= 64 && std::all_of(id.begin(), id.end(), [](char c) {
                    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                           (c >= '0' && c <= '9') || c == '-' || c == '_';
                  });
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(
      "progress_id: 1 to 64 letters, digits, '-' or '_' (e.g. a UUID)");
}

void LoadProgressRegistry::EvictLocked() {
  const auto now = std::chrono::steady_clock::now();
  for (auto it = entries_.begin(); it != entries_.end();) {
    const bool expired =
        it->second.state.done && now - it->second.finished_at > options_.keep_after_done;
    it = expired ? entries_.erase(it) : std::next(it);
  }
  while (entries_.size() >= options_.max_entries) {
    auto oldest = entries_.end();
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->second.state.done &&
          (oldest == entries_.end() || it->second.finished_at < oldest->second.finished_at)) {
        oldest = it;
      }
    }
    if (oldest == entries_.end()) return;  // every entry is a running load
    entries_.erase(oldest);
  }
}

std::string LoadProgressRegistry::Key(std::string_view user, std::string_view id) {
  return StrCat(user, "\n", id);  // user names hold no newline
}

Status LoadProgressRegistry::Start(std::string_view user, const std::string& id) {
  RETURN_IF_ERROR(CheckId(id));
  std::lock_guard lock(mutex_);
  EvictLocked();
  auto it = entries_.find(Key(user, id));
  if (it != entries_.end() && !it->second.state.done) {
    return absl::AlreadyExistsError(StrCat("progress_id '", id, "': a load with it is running"));
  }
  if (it == entries_.end() && entries_.size() >= options_.max_entries) {
    return absl::ResourceExhaustedError(
        StrCat("progress_id: ", options_.max_entries, " followed loads run already"));
  }
  entries_[Key(user, id)] = Entry{LoadProgressState{0.0, "queued", false, absl::OkStatus()}, {}};
  return absl::OkStatus();
}

ProgressFn LoadProgressRegistry::Reporter(std::string_view user, const std::string& id) {
  return [this, key = Key(user, id)](double fraction, std::string_view stage) {
    std::lock_guard lock(mutex_);
    auto it = entries_.find(key);
    if (it == entries_.end() || it->second.state.done) return;
    LoadProgressState& s = it->second.state;
    s.fraction = std::max(s.fraction, std::clamp(fraction, 0.0, 1.0));
    s.stage = std::string(stage);
  };
}

void LoadProgressRegistry::Finish(std::string_view user, const std::string& id,
                                  const Status& status) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(Key(user, id));
  if (it == entries_.end() || it->second.state.done) return;
  LoadProgressState& s = it->second.state;
  s.done = true;
  s.status = status;
  if (status.ok()) {
    s.fraction = 1.0;
    s.stage = "done";
  } else {
    s.stage = "failed";
  }
  it->second.finished_at = std::chrono::steady_clock::now();
}

Result<LoadProgressState> LoadProgressRegistry::Get(std::string_view user,
                                                    const std::string& id) const {
  RETURN_IF_ERROR(CheckId(id));
  std::lock_guard lock(mutex_);
  auto it = entries_.find(Key(user, id));
  if (it == entries_.end()) {
    return absl::NotFoundError(StrCat("progress_id '", id, "': no load with it (yet)"));
  }
  return it->second.state;
}

}  // namespace vpm::service

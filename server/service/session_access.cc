#include "server/service/session_access.h"

namespace vpm::service {

Status SessionNotFound() {
  return absl::NotFoundError("session_id: no such session of yours or shared with you");
}

void SessionAccess::Share(const std::string& user, bool shared) {
  std::lock_guard lock(mutex_);
  if (shared) {
    viewers_.insert(user);
  } else {
    viewers_.erase(user);
  }
}

std::vector<std::string> SessionAccess::viewers() const {
  std::lock_guard lock(mutex_);
  return {viewers_.begin(), viewers_.end()};
}

Status SessionAccess::Check(std::string_view user, SessionRole role,
                            std::string_view session_id) const {
  if (IsOwner(user)) return absl::OkStatus();
  bool viewer = false;
  {
    std::lock_guard lock(mutex_);
    viewer = viewers_.contains(user);
  }
  if (viewer && role == SessionRole::kViewer) return absl::OkStatus();
  if (viewer) {
    return absl::PermissionDeniedError(
        StrCat("session_id: session '", session_id,
               "' is shared with you to watch; only its owner may change it"));
  }
  return SessionNotFound();
}

}  // namespace vpm::service

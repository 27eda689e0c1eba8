// Who may do what with one session. The user who opened it owns it and alone
// drives it (Interact, Manipulate, SetCamera), shares it and closes it. The
// owner may share it with other users by name: they are viewers, who may
// Watch it, Render stills of it and read it (GetSession, ListSessions) but
// never deform it or move its camera. Everyone else gets the answer a
// missing session gets (SessionNotFound), so that no user learns which ids
// exist.
#pragma once

#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "server/common/status.h"

namespace vpm::service {

// The one answer for a session id that does not exist and for one that is
// not the caller's: NotFound, the same text, without the id.
Status SessionNotFound();

enum class SessionRole {
  kViewer,  // Watch, Render, GetSession
  kOwner,   // Interact, Manipulate, SetCamera, ShareSession, CloseSession
};

class SessionAccess {
 public:
  explicit SessionAccess(std::string owner) : owner_(std::move(owner)) {}

  const std::string& owner() const { return owner_; }
  bool IsOwner(std::string_view user) const { return user == owner_; }
  // Lets `user` watch (true) or no longer watch (false).
  void Share(const std::string& user, bool shared);
  std::vector<std::string> viewers() const;  // sorted
  // OK when `user` has `role` (an owner is a viewer too); PermissionDenied
  // for a viewer asking for the owner's role; SessionNotFound for anyone else.
  // `session_id` names the session in the message.
  Status Check(std::string_view user, SessionRole role, std::string_view session_id) const;

 private:
  const std::string owner_;
  mutable std::mutex mutex_;
  std::set<std::string, std::less<>> viewers_;
};

}  // namespace vpm::service

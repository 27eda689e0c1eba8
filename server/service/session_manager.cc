#include "server/service/session_manager.h"

#include <set>

#include "server/common/random_hex.h"

namespace vpm::service {

Result<std::unique_ptr<SessionManager>> SessionManager::Create(const Options& options) {
  if (options.context == nullptr) {
    return absl::InvalidArgumentError("SessionManager: no GPU context");
  }
  return std::unique_ptr<SessionManager>(new SessionManager(options));
}

Status SessionManager::CheckMeshRoomLocked(const std::string& owner,
                                           const std::string& mesh_id) const {
  if (options_.max_meshes_per_user <= 0) return absl::OkStatus();
  std::set<std::string> pinned;
  for (const auto& [id, session] : sessions_) {
    if (session->access().IsOwner(owner)) pinned.insert(session->mesh()->id);
  }
  for (auto [it, end] = opening_meshes_.equal_range(owner); it != end; ++it) {
    pinned.insert(it->second);
  }
  if (pinned.contains(mesh_id) ||
      static_cast<int64_t>(pinned.size()) < options_.max_meshes_per_user) {
    return absl::OkStatus();
  }
  return absl::ResourceExhaustedError(
      StrCat("your sessions use ", pinned.size(),
             " meshes, the most one user's may "
             "(--max-meshes-per-user); open the session on a mesh you use, or close one"));
}

Result<std::shared_ptr<Session>> SessionManager::Open(const std::string& owner, VolumeHold volume,
                                                      std::shared_ptr<const MeshEntry> mesh) {
  std::string id;
  std::multimap<std::string, std::string>::iterator opening_mesh;
  {
    std::lock_guard lock(mutex_);
    if (static_cast<int64_t>(sessions_.size()) + opening_ >= options_.max_sessions) {
      return absl::ResourceExhaustedError(StrCat("the server holds its maximum of ",
                                                 options_.max_sessions,
                                                 " sessions; close one first"));
    }
    if (options_.max_sessions_per_user > 0) {
      int64_t owned = opening_per_user_[owner];
      for (const auto& [other_id, session] : sessions_) owned += session->access().IsOwner(owner);
      if (owned >= options_.max_sessions_per_user) {
        if (opening_per_user_[owner] == 0) opening_per_user_.erase(owner);
        return absl::ResourceExhaustedError(StrCat("user '", owner, "' holds the maximum of ",
                                                   options_.max_sessions_per_user,
                                                   " sessions per user; close one first"));
      }
    }
    if (Status room = CheckMeshRoomLocked(owner, mesh->id); !room.ok()) {
      if (opening_per_user_[owner] == 0) opening_per_user_.erase(owner);
      return room;
    }
    ++opening_;
    ++opening_per_user_[owner];
    opening_mesh = opening_meshes_.emplace(owner, mesh->id);
    // 128 random bits: an id says nothing of the others, and cannot be guessed.
    id = StrCat(options_.id_prefix, RandomHex(16));
  }
  auto session = Session::Create(id, owner, *options_.context, std::move(volume),
                                 std::move(mesh), options_.session);
  std::lock_guard lock(mutex_);
  --opening_;
  if (--opening_per_user_[owner] <= 0) opening_per_user_.erase(owner);
  opening_meshes_.erase(opening_mesh);
  if (!session.ok()) return session.status();
  sessions_.emplace(id, *session);
  NotifyLocked();
  return *session;
}

Result<std::shared_ptr<Session>> SessionManager::Get(std::string_view id, std::string_view user,
                                                     SessionRole role) const {
  std::lock_guard lock(mutex_);
  auto it = sessions_.find(id);
  if (it == sessions_.end()) return SessionNotFound();
  RETURN_IF_ERROR(it->second->access().Check(user, role, id));
  it->second->Touch();
  return it->second;
}

Status SessionManager::Close(std::string_view id, std::string_view user) {
  std::shared_ptr<Session> session;
  {
    std::lock_guard lock(mutex_);
    auto it = sessions_.find(id);
    if (it == sessions_.end()) return SessionNotFound();
    RETURN_IF_ERROR(it->second->access().Check(user, SessionRole::kOwner, id));
    session = it->second;
    sessions_.erase(it);
    NotifyLocked();
  }
  session->Close();
  return absl::OkStatus();
}

std::vector<std::shared_ptr<Session>> SessionManager::List(std::string_view user) const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<Session>> out;
  for (const auto& [id, session] : sessions_) {
    if (session->access().Check(user, SessionRole::kViewer, id).ok()) out.push_back(session);
  }
  return out;
}

int SessionManager::EvictIdle() {
  auto idle_past = [](double idle_s, double limit_s) { return limit_s > 0 && idle_s > limit_s; };
  std::vector<std::shared_ptr<Session>> evicted;
  {
    std::lock_guard lock(mutex_);
    for (auto it = sessions_.begin(); it != sessions_.end();) {
      const Session& s = *it->second;
      if (idle_past(s.idle_s(), s.viewers() == 0 ? options_.idle_session_s
                                                 : options_.idle_watched_session_s)) {
        evicted.push_back(it->second);
        it = sessions_.erase(it);
      } else {
        ++it;
      }
    }
    if (!evicted.empty()) NotifyLocked();
  }
  for (auto& session : evicted) session->Close();
  return static_cast<int>(evicted.size());
}

void SessionManager::CloseAll() {
  std::map<std::string, std::shared_ptr<Session>, std::less<>> sessions;
  {
    std::lock_guard lock(mutex_);
    sessions.swap(sessions_);
    NotifyLocked();
  }
  for (auto& [id, session] : sessions) session->Close();
}

void SessionManager::NotifyLocked() const {
  if (!options_.on_change) return;
  std::map<std::string, int64_t> per_user;
  for (auto& [user, count] : reported_) per_user[user] = 0;
  for (const auto& [id, session] : sessions_) ++per_user[session->access().owner()];
  options_.on_change(static_cast<int64_t>(sessions_.size()), per_user);
  reported_.clear();
  for (const auto& [user, count] : per_user) {
    if (count > 0) reported_[user] = count;
  }
}

}  // namespace vpm::service

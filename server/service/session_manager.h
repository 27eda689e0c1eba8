// The open sessions: created on a volume and mesh by a user (their owner),
// looked up by id for a user in a role (session_access.h), closed by their
// owner, or evicted: after idle_session_s without calls or viewers (the
// last stream ended), or after idle_watched_session_s watched but driven by
// nobody (no event, camera move or call naming it).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "server/service/session.h"

namespace vpm::service {

class SessionManager {
 public:
  struct Options {
    const gpu::GpuContext* context = nullptr;  // outlive the manager
    int64_t max_sessions = 32;
    int64_t max_sessions_per_user = 16;    // 0: only max_sessions
    // Meshes one user's sessions pin (0: no cap): a pinned mesh cannot be
    // evicted, so without it one user's sessions could pin every mesh slot.
    int64_t max_meshes_per_user = 0;
    double idle_session_s = 900;           // no viewer; 0: never evict
    double idle_watched_session_s = 3600;  // viewers but no driver; 0: never
    Session::Options session;
    // Metrics: sessions open, and per owner (users whose count fell to zero
    // are reported with 0 once).
    std::function<void(int64_t open, const std::map<std::string, int64_t>& per_user)> on_change;
    std::string id_prefix = "ses-";  // ids are id_prefix + 32 random hex digits
  };
  static Result<std::unique_ptr<SessionManager>> Create(const Options& options);

  // Builds the scene (FEM set-up): call from a worker. `volume`: the
  // owner's hold on the mesh's volume (VolumeStore::HoldForSession).
  // ResourceExhausted past max_sessions, the owner's max_sessions_per_user
  // or max_meshes_per_user (a mesh none of their sessions pins yet).
  Result<std::shared_ptr<Session>> Open(const std::string& owner, VolumeHold volume,
                                        std::shared_ptr<const MeshEntry> mesh);
  // NotFound (SessionNotFound) when missing or not shared with `user`;
  // PermissionDenied for a viewer asking for the owner's role; touches it.
  Result<std::shared_ptr<Session>> Get(std::string_view id, std::string_view user,
                                       SessionRole role) const;
  Status Close(std::string_view id, std::string_view user);  // as Get for the owner
  // The sessions `user` owns or views.
  std::vector<std::shared_ptr<Session>> List(std::string_view user) const;
  // Closes sessions idle past the limit with no viewer; returns how many.
  int EvictIdle();
  void CloseAll();

 private:
  explicit SessionManager(Options options) : options_(std::move(options)) {}
  void NotifyLocked() const;
  // ResourceExhausted when `owner`'s sessions (open or opening) pin
  // max_meshes_per_user meshes and `mesh_id` is not one of them.
  Status CheckMeshRoomLocked(const std::string& owner, const std::string& mesh_id) const;

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Session>, std::less<>> sessions_;
  int64_t opening_ = 0;  // reserved places while scenes are built
  std::map<std::string, int64_t> opening_per_user_;
  std::multimap<std::string, std::string> opening_meshes_;  // owner -> mesh id, while opening
  mutable std::map<std::string, int64_t> reported_;  // per owner, as last reported
};

}  // namespace vpm::service

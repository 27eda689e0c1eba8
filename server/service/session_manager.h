// The open sessions: created on a volume and mesh, looked up by id, closed
// by a client, or evicted: after idle_session_s without calls or viewers
// (the last stream ended), or after idle_watched_session_s watched but
// driven by nobody (no event, camera move or call naming it).
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
    VolumeRenderer* renderer = nullptr;
    int64_t max_sessions = 32;
    double idle_session_s = 900;           // no viewer; 0: never evict
    double idle_watched_session_s = 3600;  // viewers but no driver; 0: never
    Session::Options session;
    std::function<void(int64_t open)> on_change;  // metrics
    std::string id_prefix = "ses-";  // ids are id_prefix + 1, 2, ...
  };
  static Result<std::unique_ptr<SessionManager>> Create(const Options& options);

  // Builds the scene (FEM set-up): call from a worker. ResourceExhausted
  // past max_sessions.
  Result<std::shared_ptr<Session>> Open(std::shared_ptr<VolumeEntry> volume,
                                        std::shared_ptr<const MeshEntry> mesh);
  Result<std::shared_ptr<Session>> Get(std::string_view id) const;  // NotFound; touches it
  Status Close(std::string_view id);                                 // NotFound
  std::vector<std::shared_ptr<Session>> List() const;
  // Closes sessions idle past the limit with no viewer; returns how many.
  int EvictIdle();
  void CloseAll();

 private:
  explicit SessionManager(Options options) : options_(std::move(options)) {}
  void NotifyLocked() const;

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Session>, std::less<>> sessions_;
  int64_t opening_ = 0;  // reserved places while scenes are built
  int64_t next_id_ = 1;
};

}  // namespace vpm::service

// The volumes the server holds: each read once (from the data root, a
// phantom or an upload), uploaded to the GPU once, and shared by every mesh
// and session that uses it (shared_ptr: a deleted volume lives on until its
// last session closes). When a cap (count or bytes) is reached, idle volumes
// (no session, and a source that can be read again: a phantom or a file
// under the data root, never an upload) are evicted least recently used
// first; their ids stay valid, and the next Get reads them again. Only when
// nothing can be evicted is a load refused, with a message saying what
// holds the room.
//
// Ownership: an uploaded volume belongs to the user who uploaded it; every
// other user gets PermissionDenied on it (it is not even listed). A volume
// loaded from the data root or a phantom is shared read-only: every user
// may read, list, mesh and open sessions on it (each could load the same
// source anyway), and a user may delete it only when no other user loaded
// it too (and, as for every volume, no session uses it). Its loaders are
// remembered across an eviction.
#pragma once

#include <atomic>
#include <functional>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/volume.h"

namespace vpm::service {

struct VolumeEntry {
  std::string id;
  Volume volume;
  GpuVolume gpu;
  int64_t bytes = 0;                // host values + GPU texel buffer
  // What LoadVolume loaded it from ("phantom:SPEC" or "file:" + the resolved
  // path); empty for uploads. A second load of the same key shares it.
  std::string load_key;
  // The uploader; empty for a shared volume (loaded from the data root or a
  // phantom).
  std::string owner;
  // An upload kept for its cases (cases::BlobStore::Reference,
  // "upload:SHA256/NAME"); empty otherwise. Set once, before its id is
  // answered.
  std::string upload_ref;
  std::atomic<int32_t> sessions{0};  // sessions using it (VolumeHold)
  // The owners of those sessions, with how many each: a shared volume kept
  // loaded by a user's sessions takes one of that user's volume slots.
  // Guarded by holders_mutex.
  std::map<std::string, int32_t, std::less<>> session_owners;
  mutable std::mutex holders_mutex;
  std::atomic<int64_t> last_used{0};  // a use counter, for LRU eviction
  // The scene may add a 3D image to `gpu` (export); guarded by this.
  std::mutex gpu_mutex;

  VolumeEntry(std::string id_in, Volume v, GpuVolume g, int64_t b)
      : id(std::move(id_in)), volume(std::move(v)), gpu(std::move(g)), bytes(b) {}
};

// NotFound unless `user` may use `volume`: its owner, or anyone for a
// shared volume. Another user's upload answers exactly as a missing volume
// (VolumeNotFound), so that ids say nothing of other users' volumes.
Status CheckVolumeAccess(const VolumeEntry& volume, std::string_view user);
// The one answer for "no such volume" and "not yours".
Status VolumeNotFound();

// A session's hold on its volume (VolumeStore::HoldForSession): counted in
// the volume's `sessions` and against the session's owner until destroyed.
class VolumeHold {
 public:
  VolumeHold(std::shared_ptr<VolumeEntry> volume, std::string owner);
  VolumeHold(VolumeHold&& other) noexcept = default;
  VolumeHold& operator=(VolumeHold&&) = delete;
  VolumeHold(const VolumeHold&) = delete;
  ~VolumeHold();
  const std::shared_ptr<VolumeEntry>& volume() const { return volume_; }

 private:
  std::shared_ptr<VolumeEntry> volume_;  // null once moved from
  std::string owner_;
};

class VolumeStore {
 public:
  struct Options {
    const gpu::GpuContext* context = nullptr;  // required; outlives the store
    std::filesystem::path data_root;           // empty: file loads off
    int64_t max_volumes = 16;
    int64_t max_bytes = int64_t{8} << 30;
    // Volume slots one user holds at once (0: no cap): their uploads, and
    // the shared volumes their sessions keep loaded. Neither can be evicted,
    // so without it one user's uploads or sessions could fill max_volumes;
    // an idle shared volume is evicted when room is needed and counts
    // against nobody.
    int64_t max_volumes_per_owner = 0;
    VolumeLimits read_limits;
    std::function<void(int64_t bytes, int64_t count)> on_change;  // metrics
    std::string id_prefix = "vol-";  // ids: id_prefix + 32 random hex digits
    // Called (without the store's lock) with the id of each evicted volume,
    // so that the meshes built on it are dropped too.
    std::function<void(const std::string& id)> on_evict;
    // Reads a pacs:ENDPOINT/STUDY/SERIES source for `user` (the PACS
    // gateway: access, audit, cache, retrieval); empty: pacs: sources are
    // FailedPrecondition. A PACS volume belongs to the user who loaded it,
    // like an upload, but is evicted when idle and read again (from the
    // series cache) like a file.
    std::function<Result<Volume>(std::string_view source, const std::string& user,
                                 const ProgressFn& progress, const CancelToken& cancel)>
        read_pacs;
    // Told when a LoadVolume of a pacs: source returns the volume the user
    // already holds (for the audit log).
    std::function<void(std::string_view source, const std::string& user)> on_pacs_reuse;
  };
  static Result<std::unique_ptr<VolumeStore>> Create(const Options& options);

  // `source`: phantom:SPEC, a path under the data root, a DICOM folder with
  // its "?series=" query included (resolve_data_path.h), or
  // pacs:ENDPOINT/STUDY/SERIES (Options::read_pacs; the volume is `user`'s).
  // A source already loaded (the same phantom spec, or a path resolving to
  // the same file) returns the volume held, not a second copy: delete it to
  // read the file again. Errors: those of ResolveDataSource and ReadVolume;
  // InvalidArgument for raw: sources; ResourceExhausted past max_volumes or
  // max_bytes. `user` is recorded as one of its loaders. `progress` hears
  // the read (0..0.85) and the upload (0.85..1). `cancel` is polled
  // before the read, by the readers as they read (VolumeLimits::cancel) and
  // between the read and the upload to the GPU.
  Result<std::shared_ptr<VolumeEntry>> Load(std::string_view source, const std::string& user,
                                            const ProgressFn& progress = {},
                                            const CancelToken& cancel = {});
  // A volume read from `path` (an upload's temporary file); `source` is what
  // GetVolume reports; `owner` the uploader.
  Result<std::shared_ptr<VolumeEntry>> AddFile(const std::filesystem::path& path,
                                               std::string source, std::string owner);
  // NotFound (VolumeNotFound) when missing or another user's upload; an
  // evicted volume is read again (the errors of Load).
  Result<std::shared_ptr<VolumeEntry>> Get(std::string_view id, std::string_view user);
  // The Load source that reads `volume` again (what a case keeps):
  // phantom:..., pacs:ENDPOINT/STUDY_UID/SERIES_UID, the path under the
  // data root, or an upload's upload_ref (empty when it was not kept).
  std::string ReloadSource(const VolumeEntry& volume) const;
  // A session's hold on `volume` for `owner`; ResourceExhausted when the
  // volume would be a new slot of `owner`'s (a shared volume none of their
  // sessions uses yet) past max_volumes_per_owner. Checked and counted
  // under one lock, so concurrent opens cannot pass the cap together.
  Result<VolumeHold> HoldForSession(std::shared_ptr<VolumeEntry> volume, const std::string& owner);
  // The volumes `user` may use.
  std::vector<std::shared_ptr<VolumeEntry>> List(std::string_view user) const;
  // NotFound (VolumeNotFound) when missing or another user's upload;
  // PermissionDenied for a shared volume that `user` did not load or that
  // another user loaded too;
  // FailedPrecondition while a session uses it. An evicted volume is
  // forgotten (the same permission rules).
  Status Delete(std::string_view id, const std::string& user);
  // ResourceExhausted when one more volume of `extra_bytes` would pass a cap
  // even after evicting every idle volume (which this does not do).
  Status CheckRoom(int64_t extra_bytes) const;
  // ResourceExhausted when `owner` holds max_volumes_per_owner slots.
  Status CheckOwnerRoom(std::string_view owner) const;
  int64_t total_bytes() const;
  int64_t evictions() const;

 private:
  explicit VolumeStore(Options options) : options_(std::move(options)) {}
  // `load_key` empty: an upload owned by `user`; else a shared volume
  // `user` loaded (empty `user`: an evicted volume read again, its loaders
  // kept). `id`: empty for a new one, else the id of an evicted volume read
  // again. `upload_progress` hears the upload to the GPU, which polls
  // `cancel`.
  Result<std::shared_ptr<VolumeEntry>> Add(Volume volume, std::string load_key,
                                           const std::string& user, std::string id = {},
                                           const ProgressFn& upload_progress = {},
                                           const CancelToken& cancel = {});
  Result<Volume> ReadSource(const std::string& load_key, const std::string& source,
                            const ProgressFn& progress = {}, const CancelToken& cancel = {}) const;
  std::shared_ptr<VolumeEntry> FindLoadedLocked(const std::string& load_key) const;
  // Evicts idle volumes, least recently used first, until one more of
  // `extra_bytes` fits (appending their ids to `evicted`); else
  // ResourceExhausted naming what holds the room.
  Status MakeRoomLocked(int64_t extra_bytes, std::vector<std::string>* evicted);
  void ReportEvicted(const std::vector<std::string>& evicted) const;
  // PermissionDenied unless `user` may delete the shared volume `id`: the
  // only user who loaded it.
  Status CheckSoleLoaderLocked(std::string_view id, const std::string& user) const;
  void NotifyLocked() const;
  Status CheckOwnerRoomLocked(std::string_view owner) const;
  // `owner`'s volume slots: their uploads held, and the shared volumes
  // their sessions use.
  int64_t SlotsOfLocked(std::string_view owner) const;

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<VolumeEntry>, std::less<>> volumes_;
  struct Evicted {
    std::string load_key;
    std::string source;
  };
  std::map<std::string, Evicted, std::less<>> evicted_;  // by id
  // The users who loaded each shared volume (held or evicted), by id.
  std::map<std::string, std::set<std::string>, std::less<>> loaded_by_;
  int64_t evictions_ = 0;
  int64_t total_bytes_ = 0;
};

}  // namespace vpm::service

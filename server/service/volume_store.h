// The volumes the server holds: each read once (from the data root, a
// phantom or an upload), uploaded to the GPU once, and shared by every mesh
// and session that uses it (shared_ptr: a deleted volume lives on until its
// last session closes). When a cap (count or bytes) is reached, idle volumes
// (no session, and a source that can be read again: a phantom or a file
// under the data root, never an upload) are evicted least recently used
// first; their ids stay valid, and the next Get reads them again. Only when
// nothing can be evicted is a load refused, with a message saying what
// holds the room.
#pragma once

#include <atomic>
#include <functional>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

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
  std::atomic<int32_t> sessions{0}; // sessions using it
  std::atomic<int64_t> last_used{0};  // a use counter, for LRU eviction
  // The scene may add a 3D image to `gpu` (export); guarded by this.
  std::mutex gpu_mutex;

  // Tells the renderer to drop its per-volume caches before `gpu` is freed.
  std::function<void(const GpuVolume*)> forget_gpu;

  VolumeEntry(std::string id_in, Volume v, GpuVolume g, int64_t b)
      : id(std::move(id_in)), volume(std::move(v)), gpu(std::move(g)), bytes(b) {}
  ~VolumeEntry() {
    if (forget_gpu) forget_gpu(&gpu);
  }
};

class VolumeStore {
 public:
  struct Options {
    const gpu::GpuContext* context = nullptr;  // required; outlives the store
    std::filesystem::path data_root;           // empty: file loads off
    int64_t max_volumes = 16;
    int64_t max_bytes = int64_t{8} << 30;
    VolumeLimits read_limits;
    std::function<void(int64_t bytes, int64_t count)> on_change;  // metrics
    std::function<void(const GpuVolume*)> forget_gpu;              // VolumeEntry::forget_gpu
    std::string id_prefix = "vol-";                                // ids: id_prefix + 1, 2, ...
    // Called (without the store's lock) with the id of each evicted volume,
    // so that the meshes built on it are dropped too.
    std::function<void(const std::string& id)> on_evict;
  };
  static Result<std::unique_ptr<VolumeStore>> Create(const Options& options);

  // `source`: phantom:SPEC, or a path under the data root (resolve_data_path.h).
  // A source already loaded (the same phantom spec, or a path resolving to
  // the same file) returns the volume held, not a second copy: delete it to
  // read the file again. Errors: those of ResolveDataPath and ReadVolume;
  // InvalidArgument for raw: sources; ResourceExhausted past max_volumes or
  // max_bytes.
  Result<std::shared_ptr<VolumeEntry>> Load(std::string_view source);
  // A volume read from `path` (an upload's temporary file); `source` is what
  // GetVolume reports.
  Result<std::shared_ptr<VolumeEntry>> AddFile(const std::filesystem::path& path,
                                               std::string source);
  // NotFound; an evicted volume is read again (the errors of Load).
  Result<std::shared_ptr<VolumeEntry>> Get(std::string_view id);
  std::vector<std::shared_ptr<VolumeEntry>> List() const;
  // NotFound; FailedPrecondition while a session uses it.
  Status Delete(std::string_view id);
  // ResourceExhausted when one more volume of `extra_bytes` would pass a cap
  // even after evicting every idle volume (which this does not do).
  Status CheckRoom(int64_t extra_bytes) const;
  int64_t total_bytes() const;
  int64_t evictions() const;

 private:
  explicit VolumeStore(Options options) : options_(std::move(options)) {}
  // `id`: empty for a new one, else the id of an evicted volume read again.
  Result<std::shared_ptr<VolumeEntry>> Add(Volume volume, std::string load_key,
                                           std::string id = {});
  Result<Volume> ReadSource(const std::string& load_key, const std::string& source) const;
  std::shared_ptr<VolumeEntry> FindLoadedLocked(const std::string& load_key) const;
  // Evicts idle volumes, least recently used first, until one more of
  // `extra_bytes` fits (appending their ids to `evicted`); else
  // ResourceExhausted naming what holds the room.
  Status MakeRoomLocked(int64_t extra_bytes, std::vector<std::string>* evicted);
  void ReportEvicted(const std::vector<std::string>& evicted) const;
  void NotifyLocked() const;

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<VolumeEntry>, std::less<>> volumes_;
  struct Evicted {
    std::string load_key;
    std::string source;
  };
  std::map<std::string, Evicted, std::less<>> evicted_;  // by id
  int64_t evictions_ = 0;
  int64_t total_bytes_ = 0;
  int64_t next_id_ = 1;
};

}  // namespace vpm::service

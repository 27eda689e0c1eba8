// The volumes the server holds: each read once (from the data root, a
// phantom or an upload), uploaded to the GPU once, and shared by every mesh
// and session that uses it (shared_ptr: a deleted volume lives on until its
// last session closes).
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
  };
  static Result<std::unique_ptr<VolumeStore>> Create(const Options& options);

  // `source`: phantom:SPEC, or a path under the data root (resolve_data_path.h).
  // A source already loaded (the same phantom spec, or a path resolving to
  // the same file) returns the volume held, not a second copy: delete it to
  // read the file again. Errors: those of ResolveDataPath and ReadVolume;
  // InvalidArgument for raw: sources; ResourceExhausted past max_volumes or
  // max_bytes.
  // `progress` hears the read (0..0.85) and the upload (0.85..1).
  Result<std::shared_ptr<VolumeEntry>> Load(std::string_view source,
                                            const ProgressFn& progress = {});
  // A volume read from `path` (an upload's temporary file); `source` is what
  // GetVolume reports.
  Result<std::shared_ptr<VolumeEntry>> AddFile(const std::filesystem::path& path,
                                               std::string source);
  Result<std::shared_ptr<VolumeEntry>> Get(std::string_view id) const;  // NotFound
  std::vector<std::shared_ptr<VolumeEntry>> List() const;
  // NotFound; FailedPrecondition while a session uses it.
  Status Delete(std::string_view id);
  // ResourceExhausted when `extra_bytes` more would pass a cap.
  Status CheckRoom(int64_t extra_bytes) const;
  int64_t total_bytes() const;

 private:
  explicit VolumeStore(Options options) : options_(std::move(options)) {}
  Result<std::shared_ptr<VolumeEntry>> Add(Volume volume, std::string load_key,
                                           const ProgressFn& upload_progress = {});
  std::shared_ptr<VolumeEntry> FindLoadedLocked(const std::string& load_key) const;
  void NotifyLocked() const;

  Options options_;
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<VolumeEntry>, std::less<>> volumes_;
  int64_t total_bytes_ = 0;
  int64_t next_id_ = 1;
};

}  // namespace vpm::service

#include "server/service/volume_store.h"

#include "server/service/resolve_data_path.h"
#include "server/io/read_volume.h"

namespace vpm::service {

Result<std::unique_ptr<VolumeStore>> VolumeStore::Create(const Options& options) {
  if (options.context == nullptr) return absl::InvalidArgumentError("VolumeStore: no GPU context");
  if (options.max_volumes < 1 || options.max_bytes < 1) {
    return absl::InvalidArgumentError("VolumeStore: max_volumes and max_bytes must be positive");
  }
  return std::unique_ptr<VolumeStore>(new VolumeStore(options));
}

Status VolumeStore::CheckRoom(int64_t extra_bytes) const {
  std::lock_guard lock(mutex_);
  if (static_cast<int64_t>(volumes_.size()) >= options_.max_volumes) {
    return absl::ResourceExhaustedError(
        StrCat("the server holds its maximum of ", options_.max_volumes,
               " volumes; delete one first"));
  }
  if (total_bytes_ + extra_bytes > options_.max_bytes) {
    return absl::ResourceExhaustedError(
        StrCat("volume bytes: ", total_bytes_, " held + ", extra_bytes, " would pass the cap of ",
               options_.max_bytes));
  }
  return absl::OkStatus();
}

std::shared_ptr<VolumeEntry> VolumeStore::FindLoadedLocked(const std::string& load_key) const {
  for (const auto& [id, entry] : volumes_) {
    if (!load_key.empty() && entry->load_key == load_key) return entry;
  }
  return nullptr;
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Load(std::string_view source,
                                                       const ProgressFn& progress) {
  if (source.starts_with("raw:")) {
    return absl::InvalidArgumentError(
        "source: raw: sources are not served; upload the file instead");
  }
  std::string key(source);
  std::string read_from(source);  // phantom spec, or the resolved file path
  if (!source.starts_with("phantom:")) {
    ASSIGN_OR_RETURN(std::filesystem::path path, ResolveDataPath(options_.data_root, source));
    read_from = path.string();
    key = "file:" + read_from;
  }
  {
    std::lock_guard lock(mutex_);
    if (auto loaded = FindLoadedLocked(key)) return loaded;
  }
  RETURN_IF_ERROR(CheckRoom(0));
  ASSIGN_OR_RETURN(Volume volume, ReadVolume(read_from, options_.read_limits,
                                             SubProgress(progress, 0.0, 0.85)));
  volume.set_source(std::string(source));
  return Add(std::move(volume), std::move(key), SubProgress(progress, 0.85, 1.0));
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::AddFile(const std::filesystem::path& path,
                                                          std::string source) {
  RETURN_IF_ERROR(CheckRoom(0));
  ASSIGN_OR_RETURN(Volume volume, ReadVolume(path.string(), options_.read_limits));
  volume.set_source(std::move(source));
  return Add(std::move(volume), "");
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Add(Volume volume, std::string load_key,
                                                      const ProgressFn& upload_progress) {
  // Host values + the GPU's texel buffer, both as the volume holds them.
  const int64_t bytes = volume.value_bytes() * 2;
  RETURN_IF_ERROR(CheckRoom(bytes));
  ASSIGN_OR_RETURN(GpuVolume gpu, GpuVolume::Upload(*options_.context, volume, upload_progress));
  std::lock_guard lock(mutex_);
  // A load of the same source that landed while this one read wins.
  if (auto loaded = FindLoadedLocked(load_key)) return loaded;
  // Checked again: another load may have landed while this one read.
  if (static_cast<int64_t>(volumes_.size()) >= options_.max_volumes ||
      total_bytes_ + bytes > options_.max_bytes) {
    return absl::ResourceExhaustedError("volume caps reached while loading; delete a volume");
  }
  std::string id = StrCat("vol-", next_id_++);
  auto entry = std::make_shared<VolumeEntry>(id, std::move(volume), std::move(gpu), bytes);
  entry->forget_gpu = options_.forget_gpu;
  entry->load_key = std::move(load_key);
  volumes_.emplace(id, entry);
  total_bytes_ += bytes;
  NotifyLocked();
  return entry;
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Get(std::string_view id) const {
  std::lock_guard lock(mutex_);
  auto it = volumes_.find(id);
  if (it == volumes_.end()) return absl::NotFoundError(StrCat("volume_id: no volume '", id, "'"));
  return it->second;
}

std::vector<std::shared_ptr<VolumeEntry>> VolumeStore::List() const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<VolumeEntry>> out;
  for (const auto& [id, entry] : volumes_) out.push_back(entry);
  return out;
}

Status VolumeStore::Delete(std::string_view id) {
  std::lock_guard lock(mutex_);
  auto it = volumes_.find(id);
  if (it == volumes_.end()) return absl::NotFoundError(StrCat("volume_id: no volume '", id, "'"));
  if (it->second->sessions.load() > 0) {
    return absl::FailedPreconditionError(StrCat("volume '", id, "' is used by ",
                                                it->second->sessions.load(),
                                                " session(s); close them first"));
  }
  total_bytes_ -= it->second->bytes;
  volumes_.erase(it);
  NotifyLocked();
  return absl::OkStatus();
}

int64_t VolumeStore::total_bytes() const {
  std::lock_guard lock(mutex_);
  return total_bytes_;
}

void VolumeStore::NotifyLocked() const {
  if (options_.on_change) options_.on_change(total_bytes_, static_cast<int64_t>(volumes_.size()));
}

}  // namespace vpm::service

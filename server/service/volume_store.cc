#include "server/service/volume_store.h"

#include <atomic>

#include "server/common/random_hex.h"
#include "server/io/read_volume.h"
#include "server/service/resolve_data_path.h"

namespace vpm::service {

Status VolumeNotFound() {
  return absl::NotFoundError("volume_id: no such volume of yours or shared");
}

Status CheckVolumeAccess(const VolumeEntry& volume, std::string_view user) {
  if (volume.owner.empty() || volume.owner == user) return absl::OkStatus();
  return VolumeNotFound();
}

VolumeHold::VolumeHold(std::shared_ptr<VolumeEntry> volume, std::string owner)
    : volume_(std::move(volume)), owner_(std::move(owner)) {
  std::lock_guard lock(volume_->holders_mutex);
  ++volume_->session_owners[owner_];
  volume_->sessions.fetch_add(1);
}

VolumeHold::~VolumeHold() {
  if (!volume_) return;
  std::lock_guard lock(volume_->holders_mutex);
  auto it = volume_->session_owners.find(owner_);
  if (it != volume_->session_owners.end() && --it->second <= 0) {
    volume_->session_owners.erase(it);
  }
  volume_->sessions.fetch_sub(1);
}

Result<std::unique_ptr<VolumeStore>> VolumeStore::Create(const Options& options) {
  if (options.context == nullptr) return absl::InvalidArgumentError("VolumeStore: no GPU context");
  if (options.max_volumes < 1 || options.max_bytes < 1) {
    return absl::InvalidArgumentError("VolumeStore: max_volumes and max_bytes must be positive");
  }
  return std::unique_ptr<VolumeStore>(new VolumeStore(options));
}

namespace {

// A use counter, not a clock: two uses within one clock tick still order.
int64_t NextUse() {
  static std::atomic<int64_t> uses{0};
  return ++uses;
}

// A PACS volume's load key: "pacs:ENDPOINT/STUDY/SERIES#USER" (user names
// hold no '#'), one per user: a PACS volume belongs to its loader.
constexpr std::string_view kPacsKeyPrefix = "pacs:";

std::string PacsKey(std::string_view source, std::string_view user) {
  return StrCat(source, "#", user);
}

std::string PacsKeyOwner(std::string_view key) {
  return std::string(key.substr(key.rfind('#') + 1));
}

std::string_view PacsKeySource(std::string_view key) { return key.substr(0, key.rfind('#')); }

// A volume no session uses and whose source can be read again.
bool Evictable(const VolumeEntry& entry) {
  return entry.sessions.load() == 0 && !entry.load_key.empty();
}

}  // namespace

Status VolumeStore::CheckRoom(int64_t extra_bytes) const {
  std::lock_guard lock(mutex_);
  int64_t count = 0, bytes = 0;  // what cannot be evicted
  for (const auto& [id, entry] : volumes_) {
    if (!Evictable(*entry)) {
      ++count;
      bytes += entry->bytes;
    }
  }
  if (count >= options_.max_volumes || bytes + extra_bytes > options_.max_bytes) {
    return absl::ResourceExhaustedError(
        StrCat("the server's volumes are all in use (", count, " of at most ",
               options_.max_volumes, ", ", bytes, " of ", options_.max_bytes,
               " bytes, held by sessions or uploads); close a session or delete a volume"));
  }
  return absl::OkStatus();
}

Status VolumeStore::MakeRoomLocked(int64_t extra_bytes, std::vector<std::string>* evicted) {
  auto fits = [&] {
    return static_cast<int64_t>(volumes_.size()) < options_.max_volumes &&
           total_bytes_ + extra_bytes <= options_.max_bytes;
  };
  while (!fits()) {
    auto lru = volumes_.end();
    for (auto it = volumes_.begin(); it != volumes_.end(); ++it) {
      if (Evictable(*it->second) &&
          (lru == volumes_.end() || it->second->last_used < lru->second->last_used)) {
        lru = it;
      }
    }
    if (lru == volumes_.end()) {
      std::string held;
      for (const auto& [id, entry] : volumes_) {
        held += StrCat(held.empty() ? "" : ", ", id, " (",
                       entry->load_key.empty() ? "an upload"
                                               : StrCat(entry->sessions.load(), " session(s)"),
                       ", ", entry->bytes, " bytes)");
      }
      return absl::ResourceExhaustedError(
          StrCat("volume caps (", options_.max_volumes, " volumes, ", options_.max_bytes,
                 " bytes) reached and nothing is idle: ", held,
                 "; close a session or delete a volume"));
    }
    evicted_[lru->first] = Evicted{lru->second->load_key, lru->second->volume.source()};
    evicted->push_back(lru->first);
    total_bytes_ -= lru->second->bytes;
    ++evictions_;
    volumes_.erase(lru);
  }
  return absl::OkStatus();
}

void VolumeStore::ReportEvicted(const std::vector<std::string>& evicted) const {
  if (!options_.on_evict) return;
  for (const std::string& id : evicted) options_.on_evict(id);
}

std::shared_ptr<VolumeEntry> VolumeStore::FindLoadedLocked(const std::string& load_key) const {
  for (const auto& [id, entry] : volumes_) {
    if (!load_key.empty() && entry->load_key == load_key) return entry;
  }
  return nullptr;
}

Result<Volume> VolumeStore::ReadSource(const std::string& load_key, const std::string& source,
                                       const ProgressFn& progress,
                                       const CancelToken& cancel) const {
  VolumeLimits limits = options_.read_limits;
  limits.cancel = cancel;  // the readers poll it as they read
  if (load_key.starts_with(kPacsKeyPrefix)) {
    if (!options_.read_pacs) {
      return absl::FailedPreconditionError(
          "source: this server has no PACS endpoints (vpm-server --pacs FILE)");
    }
    return options_.read_pacs(PacsKeySource(load_key), PacsKeyOwner(load_key), progress, cancel);
  }
  if (!load_key.starts_with("file:")) {
    ASSIGN_OR_RETURN(Volume volume, ReadVolume(load_key, limits, progress));
    volume.set_source(source);
    return volume;
  }
  // Every file the reader opens stays inside the data root; messages name
  // files relative to it.
  ASSIGN_OR_RETURN(limits.read_root, CanonicalDataRoot(options_.data_root));
  Result<Volume> read = ReadVolume(load_key.substr(5), limits, progress);
  if (!read.ok()) return HideFolder(read.status(), limits.read_root, "the data root");
  Volume volume = *std::move(read);
  volume.set_source(source);
  return volume;
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Load(std::string_view source,
                                                       const std::string& user,
                                                       const ProgressFn& progress,
                                                       const CancelToken& cancel) {
  if (source.starts_with("raw:")) {
    return absl::InvalidArgumentError(
        "source: raw: sources are not served; upload the file instead");
  }
  std::string key(source);
  const bool pacs = source.starts_with(kPacsKeyPrefix);
  if (pacs) {
    key = PacsKey(source, user);
  } else if (!source.starts_with("phantom:")) {
    ASSIGN_OR_RETURN(const std::string path, ResolveDataSource(options_.data_root, source));
    key = "file:" + path;
  }
  {
    std::lock_guard lock(mutex_);
    if (auto loaded = FindLoadedLocked(key)) {
      loaded->last_used = NextUse();
      if (!pacs) loaded_by_[loaded->id].insert(user);
      if (pacs && options_.on_pacs_reuse) options_.on_pacs_reuse(source, user);
      return loaded;
    }
  }
  RETURN_IF_ERROR(CheckRoom(0));
  RETURN_IF_ERROR(cancel.Check());
  ASSIGN_OR_RETURN(Volume volume,
                   ReadSource(key, std::string(source), SubProgress(progress, 0.0, 0.85), cancel));
  RETURN_IF_ERROR(cancel.Check());
  return Add(std::move(volume), std::move(key), user, {}, SubProgress(progress, 0.85, 1.0),
             cancel);
}

std::string VolumeStore::ReloadSource(const VolumeEntry& volume) const {
  const std::string& key = volume.load_key;
  if (key.starts_with(kPacsKeyPrefix)) return std::string(PacsKeySource(key));
  if (key.empty()) return volume.upload_ref;  // an upload: kept, or "" when not
  if (!key.starts_with("file:")) return key;  // phantom:...
  Result<std::filesystem::path> root = CanonicalDataRoot(options_.data_root);
  if (!root.ok()) return "";
  return std::filesystem::path(key.substr(5)).lexically_relative(*root).string();
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::AddFile(const std::filesystem::path& path,
                                                          std::string source, std::string owner) {
  RETURN_IF_ERROR(CheckRoom(0));
  VolumeLimits limits = options_.read_limits;  // the file's own folder is its root
  std::error_code error;
  limits.read_root = std::filesystem::canonical(path.parent_path(), error);
  if (error) return absl::InternalError("upload: the temporary folder is gone");
  ASSIGN_OR_RETURN(Volume volume, ReadVolume(path.string(), limits));
  volume.set_source(std::move(source));
  return Add(std::move(volume), "", owner);
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Add(Volume volume, std::string load_key,
                                                      const std::string& user, std::string id,
                                                      const ProgressFn& upload_progress,
                                                      const CancelToken& cancel) {
  // Host values + the GPU's texel buffer (voxels in pairs: twice the host's
  // bytes, server/volume/gpu_volume.h).
  const int64_t bytes =
      volume.value_bytes() +
      int64_t(GpuVolume::BufferBytesFor(volume.encoding(), uint64_t(volume.geometry().voxel_count()),
                                        options_.context->limits().maxTexelBufferElements));
  RETURN_IF_ERROR(CheckRoom(bytes));
  ASSIGN_OR_RETURN(GpuVolume gpu, GpuVolume::Upload(*options_.context, volume, upload_progress,
                                                    std::nullopt, cancel));
  std::vector<std::string> evicted;
  std::shared_ptr<VolumeEntry> entry;
  Status room;
  {
    std::lock_guard lock(mutex_);
    // A load of the same source that landed while this one read wins.
    if (auto loaded = FindLoadedLocked(load_key)) {
      if (!user.empty()) loaded_by_[loaded->id].insert(user);
      return loaded;
    }
    if (load_key.empty()) room = CheckOwnerRoomLocked(user);
    if (room.ok()) room = MakeRoomLocked(bytes, &evicted);
    if (room.ok()) {
      if (id.empty()) {
        // 128 random bits: an id says nothing of the others, nor can it be
        // guessed.
        id = StrCat(options_.id_prefix, RandomHex(16));
      } else {
        evicted_.erase(id);
      }
      entry = std::make_shared<VolumeEntry>(id, std::move(volume), std::move(gpu), bytes);
      if (load_key.empty()) {
        entry->owner = user;
      } else if (load_key.starts_with(kPacsKeyPrefix)) {
        entry->owner = PacsKeyOwner(load_key);
      } else if (!user.empty()) {
        loaded_by_[id].insert(user);
      }
      entry->load_key = std::move(load_key);
      entry->last_used = NextUse();
      volumes_.emplace(id, entry);
      total_bytes_ += bytes;
    }
    NotifyLocked();
  }
  // Evictions made before a refusal stand too (their volumes were idle).
  ReportEvicted(evicted);
  if (!room.ok()) return room;
  return entry;
}

Result<std::shared_ptr<VolumeEntry>> VolumeStore::Get(std::string_view id,
                                                      std::string_view user) {
  Evicted again;
  {
    std::lock_guard lock(mutex_);
    auto it = volumes_.find(id);
    if (it != volumes_.end()) {
      RETURN_IF_ERROR(CheckVolumeAccess(*it->second, user));
      it->second->last_used = NextUse();
      return it->second;
    }
    auto gone = evicted_.find(id);
    if (gone == evicted_.end()) return VolumeNotFound();
    again = gone->second;
  }
  if (again.load_key.starts_with(kPacsKeyPrefix) && PacsKeyOwner(again.load_key) != user) {
    return VolumeNotFound();  // another user's PACS volume: as a missing one
  }
  // Evicted while idle (a shared volume: anyone may read it): read it again
  // under its id, its loaders kept.
  {
    std::lock_guard lock(mutex_);
    if (auto loaded = FindLoadedLocked(again.load_key)) return loaded;  // reloaded meanwhile
  }
  ASSIGN_OR_RETURN(Volume volume, ReadSource(again.load_key, again.source));
  return Add(std::move(volume), again.load_key, "", std::string(id));
}

std::vector<std::shared_ptr<VolumeEntry>> VolumeStore::List(std::string_view user) const {
  std::lock_guard lock(mutex_);
  std::vector<std::shared_ptr<VolumeEntry>> out;
  for (const auto& [id, entry] : volumes_) {
    if (CheckVolumeAccess(*entry, user).ok()) out.push_back(entry);
  }
  return out;
}

Status VolumeStore::CheckSoleLoaderLocked(std::string_view id, const std::string& user) const {
  auto it = loaded_by_.find(id);
  const bool loaded_it = it != loaded_by_.end() && it->second.contains(user);
  if (loaded_it && it->second.size() == 1) return absl::OkStatus();
  return absl::PermissionDeniedError(
      StrCat("volume '", id, "' is shared: ",
             loaded_it ? "other users loaded it too" : "you did not load it",
             "; only a user who alone loaded it may delete it"));
}

Status VolumeStore::Delete(std::string_view id, const std::string& user) {
  std::lock_guard lock(mutex_);
  if (auto gone = evicted_.find(id); gone != evicted_.end()) {  // shared or PACS volumes
    if (gone->second.load_key.starts_with(kPacsKeyPrefix)) {
      if (PacsKeyOwner(gone->second.load_key) != user) {
        return absl::PermissionDeniedError(
            StrCat("volume_id: volume '", id, "' was loaded from a PACS by another user"));
      }
      evicted_.erase(gone);
      return absl::OkStatus();
    }
    RETURN_IF_ERROR(CheckSoleLoaderLocked(id, user));
    evicted_.erase(evicted_.find(id));
    loaded_by_.erase(loaded_by_.find(id));
    return absl::OkStatus();
  }
  auto it = volumes_.find(id);
  if (it == volumes_.end()) return VolumeNotFound();
  RETURN_IF_ERROR(CheckVolumeAccess(*it->second, user));
  if (it->second->owner.empty()) RETURN_IF_ERROR(CheckSoleLoaderLocked(id, user));
  if (it->second->sessions.load() > 0) {
    return absl::FailedPreconditionError(StrCat("volume '", id, "' is used by ",
                                                it->second->sessions.load(),
                                                " session(s); close them first"));
  }
  total_bytes_ -= it->second->bytes;
  if (auto loaders = loaded_by_.find(id); loaders != loaded_by_.end()) loaded_by_.erase(loaders);
  volumes_.erase(it);
  NotifyLocked();
  return absl::OkStatus();
}

Status VolumeStore::CheckOwnerRoom(std::string_view owner) const {
  std::lock_guard lock(mutex_);
  return CheckOwnerRoomLocked(owner);
}

int64_t VolumeStore::SlotsOfLocked(std::string_view owner) const {
  int64_t held = 0;
  for (const auto& [id, entry] : volumes_) {
    if (entry->owner == owner) {
      held += entry->load_key.empty();  // an upload; a PACS volume is evictable
    } else if (entry->owner.empty()) {
      std::lock_guard holders(entry->holders_mutex);
      held += entry->session_owners.contains(owner);
    }
  }
  return held;
}

Status VolumeStore::CheckOwnerRoomLocked(std::string_view owner) const {
  if (options_.max_volumes_per_owner <= 0) return absl::OkStatus();
  const int64_t held = SlotsOfLocked(owner);
  if (held < options_.max_volumes_per_owner) return absl::OkStatus();
  return absl::ResourceExhaustedError(
      StrCat("you hold ", held,
             " volumes (your uploads, and the volumes your sessions keep "
             "loaded), the most one user may (--max-volumes-per-user); close a session or "
             "delete an upload first"));
}

Result<VolumeHold> VolumeStore::HoldForSession(std::shared_ptr<VolumeEntry> volume,
                                               const std::string& owner) {
  std::lock_guard lock(mutex_);
  bool new_slot = false;
  if (volume->owner.empty()) {
    std::lock_guard holders(volume->holders_mutex);
    new_slot = !volume->session_owners.contains(owner);
  }
  if (new_slot) RETURN_IF_ERROR(CheckOwnerRoomLocked(owner));
  return VolumeHold(std::move(volume), owner);
}

int64_t VolumeStore::evictions() const {
  std::lock_guard lock(mutex_);
  return evictions_;
}

int64_t VolumeStore::total_bytes() const {
  std::lock_guard lock(mutex_);
  return total_bytes_;
}

void VolumeStore::NotifyLocked() const {
  if (options_.on_change) options_.on_change(total_bytes_, static_cast<int64_t>(volumes_.size()));
}

}  // namespace vpm::service

#include "server/service/mesh_store.h"

#include <cmath>

#include "server/common/random_hex.h"
#include "server/service/mesh_params_key.h"

namespace vpm::service {

Status MeshNotFound() { return absl::NotFoundError("mesh_id: no such mesh of yours or shared"); }

Status CheckInsideVolume(const VolumeGeometry& geometry, const glm::dvec3& point_mm,
                         std::string_view field) {
  const glm::dvec3 extent = geometry.extent_mm();
  for (int axis = 0; axis < 3; ++axis) {
    if (!std::isfinite(point_mm[axis])) {
      return absl::InvalidArgumentError(StrCat(field, ": not a finite point"));
    }
    if (point_mm[axis] < 0.0 || point_mm[axis] > extent[axis]) {
      // Said in the client's frame: world LPS, with the volume's world box.
      const glm::dvec3 w = geometry.PhysicalToWorld(point_mm);
      const std::array<glm::dvec3, 2> box = geometry.WorldBox();
      return absl::OutOfRangeError(StrCat(
          field, ": (", w.x, ", ", w.y, ", ", w.z, ") mm (world LPS) is outside the volume",
          ", whose box spans (", box[0].x, ", ", box[0].y, ", ", box[0].z, ") to (", box[1].x,
          ", ", box[1].y, ", ", box[1].z, ") mm"));
    }
  }
  return absl::OkStatus();
}

Result<std::unique_ptr<MeshStore>> MeshStore::Create(const Options& options) {
  if (options.context == nullptr) return absl::InvalidArgumentError("MeshStore: no GPU context");
  std::unique_ptr<MeshStore> store(new MeshStore(options));
  ASSIGN_OR_RETURN(LatticeCostsGpu costs, LatticeCostsGpu::Create(*options.context));
  store->costs_.emplace(std::move(costs));
  return store;
}

Result<std::shared_ptr<const MeshEntry>> MeshStore::Build(std::shared_ptr<VolumeEntry> volume,
                                                          const MeshParams& params,
                                                          const CancelToken& cancel) {
  if (params.refine_at_mm) {
    RETURN_IF_ERROR(CheckInsideVolume(volume->volume.geometry(), *params.refine_at_mm,
                                      "params.refine_at_mm"));
  }
  auto entry = std::make_shared<MeshEntry>();
  entry->key = MeshParamsKey(volume->id, params);
  {
    std::lock_guard lock(mutex_);
    if (auto held = FindLocked(entry->key)) return held;
    // Refuse before the work when every held mesh is pinned.
    RETURN_IF_ERROR(MakeRoomLocked());
  }
  entry->volume = volume;
  entry->params = params;
  {
    std::lock_guard lock(costs_mutex_);
    ASSIGN_OR_RETURN(DecimatedLattice base,
                     DecimateLattice(volume->volume, params, {&volume->gpu, &*costs_}, cancel));
    // Clients print where step 1 ran (MeshStats.evaluated_on): name the device.
    if (base.stats.evaluated_on != kStep1OnCpuReference) {
      base.stats.evaluated_on += StrCat("; Vulkan device ", options_.context->device_name());
    }
    entry->base = std::make_shared<const DecimatedLattice>(std::move(base));
  }
  ASSIGN_OR_RETURN(entry->mesh, FinishProxyMesh(volume->volume, *entry->base, params, cancel));
  return Add(std::move(entry));
}

Result<std::shared_ptr<const MeshEntry>> MeshStore::Refine(std::string_view mesh_id,
                                                           const glm::dvec3& point_mm,
                                                           const CancelToken& cancel) {
  ASSIGN_OR_RETURN(std::shared_ptr<const MeshEntry> old, Get(mesh_id));
  RETURN_IF_ERROR(CheckInsideVolume(old->volume->volume.geometry(), point_mm, "point_mm"));
  auto entry = std::make_shared<MeshEntry>();
  entry->volume = old->volume;
  entry->params = old->params;
  entry->params.refine_at_mm = point_mm;
  entry->key = MeshParamsKey(entry->volume->id, entry->params);
  {
    std::lock_guard lock(mutex_);
    if (auto held = FindLocked(entry->key)) return held;
    RETURN_IF_ERROR(MakeRoomLocked());
  }
  entry->base = old->base;
  ASSIGN_OR_RETURN(entry->mesh,
                   FinishProxyMesh(entry->volume->volume, *entry->base, entry->params, cancel));
  return Add(std::move(entry));
}

std::shared_ptr<const MeshEntry> MeshStore::FindLocked(
    const std::optional<std::string>& key) const {
  if (!key) return nullptr;
  for (const auto& [id, held] : meshes_) {
    if (held.entry->key == key) {
      held.last_used = ++tick_;
      return held.entry;
    }
  }
  return nullptr;
}

Status MeshStore::MakeRoomLocked() {
  while (static_cast<int64_t>(meshes_.size()) >= options_.max_meshes) {
    // Only the store holds an unpinned mesh. The count cannot rise from 1
    // meanwhile: new references come from this store, under this lock.
    auto oldest = meshes_.end();
    for (auto it = meshes_.begin(); it != meshes_.end(); ++it) {
      if (it->second.entry.use_count() == 1 &&
          (oldest == meshes_.end() || it->second.last_used < oldest->second.last_used)) {
        oldest = it;
      }
    }
    if (oldest == meshes_.end()) {
      return absl::ResourceExhaustedError(
          StrCat("the server holds its maximum of ", options_.max_meshes,
                 " meshes and sessions use every one of them; close a session (vpm session "
                 "close) or raise --max-meshes"));
    }
    meshes_.erase(oldest);
    ChangedLocked();
  }
  return absl::OkStatus();
}

Result<std::shared_ptr<const MeshEntry>> MeshStore::Add(std::shared_ptr<MeshEntry> entry) {
  std::lock_guard lock(mutex_);
  // Another call may have built the same mesh meanwhile: one copy is kept.
  if (auto held = FindLocked(entry->key)) return held;
  RETURN_IF_ERROR(MakeRoomLocked());
  // 128 random bits: an id says nothing of the others, nor can it be guessed.
  entry->id = StrCat(options_.id_prefix, RandomHex(16));
  meshes_.emplace(entry->id, Held{entry, ++tick_});
  ChangedLocked();
  return std::shared_ptr<const MeshEntry>(entry);
}

Result<std::shared_ptr<const MeshEntry>> MeshStore::Get(std::string_view id) const {
  std::lock_guard lock(mutex_);
  auto it = meshes_.find(id);
  if (it == meshes_.end()) return MeshNotFound();
  it->second.last_used = ++tick_;
  return it->second.entry;
}

Status MeshStore::Delete(std::string_view id) {
  std::lock_guard lock(mutex_);
  auto it = meshes_.find(id);
  if (it == meshes_.end()) return MeshNotFound();
  if (it->second.entry.use_count() > 1) {
    return absl::FailedPreconditionError(
        StrCat("mesh ", id, " is in use by a session; close the session first"));
  }
  meshes_.erase(it);
  ChangedLocked();
  return absl::OkStatus();
}

void MeshStore::ForgetVolume(std::string_view volume_id) {
  std::lock_guard lock(mutex_);
  std::erase_if(meshes_, [&](const auto& kv) { return kv.second.entry->volume->id == volume_id; });
  ChangedLocked();
}

void MeshStore::ChangedLocked() const {
  if (options_.on_change) options_.on_change(static_cast<int64_t>(meshes_.size()));
}

int64_t MeshStore::size() const {
  std::lock_guard lock(mutex_);
  return static_cast<int64_t>(meshes_.size());
}

}  // namespace vpm::service

// Proxy meshes built on the server's volumes. A mesh is immutable once
// built: RefineMesh makes a new one from the same decimated lattice (steps
// 1-2 are not redone), so sessions on the old mesh are unaffected.
//
// Lifecycle: a Build or Refine whose volume and parameters equal those of a
// held mesh returns that mesh. A mesh a session holds is pinned (the session
// keeps a reference). At the cap, unpinned meshes are evicted least recently
// used first; ResourceExhausted only when every held mesh is pinned.
// Delete drops an unpinned mesh; a pinned one is FailedPrecondition.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "server/common/status.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/service/volume_store.h"

namespace vpm::service {

struct MeshEntry {
  std::string id;
  std::optional<std::string> key;  // MeshParamsKey: equal keys, equal meshes
  std::shared_ptr<VolumeEntry> volume;
  MeshParams params;
  std::shared_ptr<const DecimatedLattice> base;  // shared by refinements
  ProxyMesh mesh;
};

// The one answer for "no such mesh" and "a mesh on another user's upload",
// so that ids say nothing of other users' meshes.
Status MeshNotFound();

class MeshStore {
 public:
  struct Options {
    const gpu::GpuContext* context = nullptr;  // step 1 on the GPU; outlives the store
    int64_t max_meshes = 64;
    std::function<void(int64_t count)> on_change;  // metrics: meshes held, after each change
    std::string id_prefix = "mesh-";               // ids: id_prefix + 32 random hex digits
  };
  static Result<std::unique_ptr<MeshStore>> Create(const Options& options);

  // Errors: InvalidArgument for bad parameters; OutOfRange for a refinement
  // point outside the volume; ResourceExhausted past max_meshes; `cancel`'s
  // status once the caller is gone (polled while the mesh is built).
  Result<std::shared_ptr<const MeshEntry>> Build(std::shared_ptr<VolumeEntry> volume,
                                                 const MeshParams& params,
                                                 const CancelToken& cancel = {});
  Result<std::shared_ptr<const MeshEntry>> Refine(std::string_view mesh_id,
                                                  const glm::dvec3& point_mm,
                                                  const CancelToken& cancel = {});
  Result<std::shared_ptr<const MeshEntry>> Get(std::string_view id) const;  // NotFound
  // NotFound, or FailedPrecondition while a session holds the mesh.
  Status Delete(std::string_view id);
  // Drops the meshes of a volume (when it is deleted).
  void ForgetVolume(std::string_view volume_id);
  int64_t size() const;

 private:
  explicit MeshStore(Options options) : options_(options) {}
  // The held mesh with this key, marked used; null if none. Under mutex_.
  std::shared_ptr<const MeshEntry> FindLocked(const std::optional<std::string>& key) const;
  // Evicts unpinned meshes, least recently used first, until one more fits;
  // ResourceExhausted naming what holds the rest. Under mutex_.
  Status MakeRoomLocked();
  Result<std::shared_ptr<const MeshEntry>> Add(std::shared_ptr<MeshEntry> entry);
  void ChangedLocked() const;

  Options options_;
  std::optional<LatticeCostsGpu> costs_;
  std::mutex costs_mutex_;  // the step-1 kernel's buffers are not shared
  mutable std::mutex mutex_;
  struct Held {
    std::shared_ptr<const MeshEntry> entry;  // use_count() == 1: no session holds it
    mutable int64_t last_used = 0;           // tick_ of the last Build, Refine or Get
  };
  std::map<std::string, Held, std::less<>> meshes_;
  mutable int64_t tick_ = 0;
};

// OutOfRange unless `point_mm` (physical mm) lies in the image box
// [0, (n-1) * spacing]; the message gives the point and box in world LPS.
Status CheckInsideVolume(const VolumeGeometry& geometry, const glm::dvec3& point_mm,
                         std::string_view field);

}  // namespace vpm::service

// Proxy meshes built on the server's volumes. A mesh is immutable once
// built: RefineMesh makes a new one from the same decimated lattice (steps
// 1-2 are not redone), so sessions on the old mesh are unaffected.
#pragma once

#include <map>
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
  std::shared_ptr<VolumeEntry> volume;
  MeshParams params;
  std::shared_ptr<const DecimatedLattice> base;  // shared by refinements
  ProxyMesh mesh;
};

class MeshStore {
 public:
  struct Options {
    const gpu::GpuContext* context = nullptr;  // step 1 on the GPU; outlives the store
    int64_t max_meshes = 64;
  };
  static Result<std::unique_ptr<MeshStore>> Create(const Options& options);

  // Errors: InvalidArgument for bad parameters; OutOfRange for a refinement
  // point outside the volume; ResourceExhausted past max_meshes.
  Result<std::shared_ptr<const MeshEntry>> Build(std::shared_ptr<VolumeEntry> volume,
                                                 const MeshParams& params);
  Result<std::shared_ptr<const MeshEntry>> Refine(std::string_view mesh_id,
                                                  const glm::dvec3& point_mm);
  Result<std::shared_ptr<const MeshEntry>> Get(std::string_view id) const;  // NotFound
  // Drops the meshes of a volume (when it is deleted).
  void ForgetVolume(std::string_view volume_id);

 private:
  explicit MeshStore(Options options) : options_(options) {}
  Result<std::shared_ptr<const MeshEntry>> Add(std::shared_ptr<MeshEntry> entry);

  Options options_;
  std::optional<LatticeCostsGpu> costs_;
  std::mutex costs_mutex_;  // the step-1 kernel's buffers are not shared
  mutable std::mutex mutex_;
  std::map<std::string, std::shared_ptr<const MeshEntry>, std::less<>> meshes_;
  int64_t next_id_ = 1;
};

// OutOfRange unless `point_mm` lies in the image box [0, (n-1) * spacing].
Status CheckInsideVolume(const VolumeGeometry& geometry, const glm::dvec3& point_mm,
                         std::string_view field);

}  // namespace vpm::service

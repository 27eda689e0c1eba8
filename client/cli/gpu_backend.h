// Where the offline commands run their GPU stages: `--backend auto` (the GPU
// when a Vulkan device opens, else the CPU reference, said on stderr),
// `gpu` (fail without one) or `cpu`.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/lattice_costs_gpu.h"
#include "server/volume/gpu_volume.h"

namespace vpm::cli {

class GpuBackend {
 public:
  // Null result (no backend) means "use the CPU".
  static Result<std::unique_ptr<GpuBackend>> Open(const std::string& backend, const Volume& volume,
                                                  const ProgressFn& upload_progress = {});

  MeshGpu mesh_gpu() const { return {&*volume_, &*lattice_costs_}; }
  const gpu::GpuContext& context() const { return *context_; }
  const GpuVolume& volume() const { return *volume_; }
  double upload_ms() const { return upload_ms_; }

 private:
  std::unique_ptr<gpu::GpuContext> context_;
  std::optional<GpuVolume> volume_;
  std::optional<LatticeCostsGpu> lattice_costs_;
  double upload_ms_ = 0.0;
};

void AddBackendFlag(CLI::App* app, std::string* backend);

}  // namespace vpm::cli

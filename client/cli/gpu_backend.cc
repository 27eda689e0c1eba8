#include "client/cli/gpu_backend.h"

#include <chrono>
#include <iostream>

#include "server/common/clock.h"

namespace vpm::cli {

void AddBackendFlag(CLI::App* app, std::string* backend) {
  app->add_option("--backend", *backend,
                  "where GPU stages run: auto (Vulkan if a device opens, else CPU), gpu, cpu")
      ->check(CLI::IsMember({"auto", "gpu", "cpu"}))
      ->capture_default_str();
}

Result<std::unique_ptr<GpuBackend>> GpuBackend::Open(const std::string& backend,
                                                     const Volume& volume,
                                                     const ProgressFn& upload_progress) {
  if (backend == "cpu") return std::unique_ptr<GpuBackend>();
  auto b = std::make_unique<GpuBackend>();
  auto context = gpu::GpuContext::Create({});
  if (!context.ok()) {
    if (backend == "gpu") return context.status();
    std::cerr << "vpm: no usable Vulkan device (" << context.status().message()
              << "); running on the CPU reference\n";
    return std::unique_ptr<GpuBackend>();
  }
  b->context_ = std::move(*context);
  const auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(GpuVolume gpu_volume, GpuVolume::Upload(*b->context_, volume, upload_progress));
  b->upload_ms_ =
      MsSince(t0);
  b->volume_.emplace(std::move(gpu_volume));
  ASSIGN_OR_RETURN(LatticeCostsGpu costs, LatticeCostsGpu::Create(*b->context_));
  b->lattice_costs_.emplace(std::move(costs));
  return b;
}

}  // namespace vpm::cli

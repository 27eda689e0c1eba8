// Step 1 on the GPU: Ci and g of every lattice vertex for both footprints.
// Two passes (shaders/lattice_costs_rows.comp: sum of TF and max |grad|^2
// per voxel-row segment of a cell; shaders/lattice_costs_cells.comp: those
// reduced per cell, plus the point footprint), in one submit and one
// readback.
// CPU reference: EvaluateLatticeCostsCpu (lattice_costs.h).
#pragma once

#include <map>
#include <memory>
#include <mutex>

#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/transfer_function.h"

namespace vpm {

class LatticeCostsGpu {
 public:
  // Row partials (8 bytes each) held at once; more go in chunks of cell
  // layers (a small budget in tests exercises the chunked path).
  static constexpr size_t kDefaultPartialsBudgetBytes = size_t{64} << 20;

  static Result<LatticeCostsGpu> Create(const gpu::GpuContext& context,
                                        size_t partials_budget_bytes = kDefaultPartialsBudgetBytes);

  // `lattice` must be built on the geometry of `volume`. gpu_ms, when given,
  // receives the kernels' GPU time.
  Result<LatticeCosts> Evaluate(const GpuVolume& volume, const Lattice& lattice,
                                const TransferFunction& tf, double* gpu_ms = nullptr) const;

  // True on a CPU device (lavapipe), where EvaluateLatticeCostsRows
  // (lattice_costs_rows.h) is faster than these kernels on the same cores.
  bool runs_on_cpu() const { return context_->is_cpu_device(); }

 private:
  // The two kernels, specialized for a transfer function of `tf_points`
  // points (docs/MESH.md: the TF loop unrolls).
  struct Kernels {
    gpu::ComputeKernel rows;
    gpu::ComputeKernel cells;
  };
  LatticeCostsGpu(const gpu::GpuContext& context, size_t partials_budget_bytes)
      : context_(&context),
        partials_budget_bytes_(partials_budget_bytes),
        mutex_(std::make_unique<std::mutex>()) {}
  // Built on first use and kept; safe to call from several threads.
  Result<const Kernels*> KernelsFor(int tf_points) const;

  const gpu::GpuContext* context_;
  size_t partials_budget_bytes_;
  std::unique_ptr<std::mutex> mutex_;
  mutable std::map<int, std::unique_ptr<Kernels>> kernels_;  // by TF point count
};

}  // namespace vpm

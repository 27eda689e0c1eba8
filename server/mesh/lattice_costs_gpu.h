// Step 1 on the GPU (shaders/lattice_costs.comp): Ci and g of every lattice
// vertex for both footprints, in one dispatch and one readback.
// CPU reference: EvaluateLatticeCostsCpu (lattice_costs.h).
#pragma once

#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/transfer_function.h"

namespace vpm {

class LatticeCostsGpu {
 public:
  static Result<LatticeCostsGpu> Create(const gpu::GpuContext& context);

  // `lattice` must be built on the geometry of `volume`. gpu_ms, when given,
  // receives the kernel's GPU time.
  Result<LatticeCosts> Evaluate(const GpuVolume& volume, const Lattice& lattice,
                                const TransferFunction& tf, double* gpu_ms = nullptr) const;

 private:
  LatticeCostsGpu(const gpu::GpuContext& context, gpu::ComputeKernel kernel)
      : context_(&context), kernel_(std::move(kernel)) {}
  const gpu::GpuContext* context_;
  gpu::ComputeKernel kernel_;
};

}  // namespace vpm

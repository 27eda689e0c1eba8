// |grad I| for every voxel on the GPU (kernel shaders/gradient_magnitude.comp).
// CPU reference: GradientMagnitude() in gradient_magnitude.h.
#pragma once

#include "server/common/status.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/volume/gpu_volume.h"

namespace vpm {

class GradientMagnitudeGpu {
 public:
  static Result<GradientMagnitudeGpu> Create(const gpu::GpuContext& context);

  // Records the kernel into `batch`; `out` is a storage buffer of at least
  // nx*ny*nz floats (value/mm, x fastest).
  Status Record(gpu::ComputeBatch& batch, const GpuVolume& volume, const gpu::GpuBuffer& out) const;

  // Convenience: runs it alone and returns the gradient, plus the GPU time.
  Result<std::vector<float>> Run(const GpuVolume& volume, double* gpu_ms = nullptr) const;

 private:
  GradientMagnitudeGpu(const gpu::GpuContext& context, gpu::ComputeKernel kernel)
      : context_(&context), kernel_(std::move(kernel)) {}
  const gpu::GpuContext* context_;
  gpu::ComputeKernel kernel_;
};

}  // namespace vpm

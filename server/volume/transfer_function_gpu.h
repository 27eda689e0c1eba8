// TF(I) for every voxel on the GPU (kernel shaders/transfer_function.comp).
// CPU reference: TransferFunction::Evaluate.
#pragma once

#include "server/common/status.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/shader_interface.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/transfer_function.h"

namespace vpm {

// The std140 uniform block for `tf`; fails if it has more than kMaxTfPoints.
Result<gpu::TransferFunctionBlock> MakeTransferFunctionBlock(const TransferFunction& tf);
// That block in a new uniform buffer, for kernels that evaluate TF.
Result<gpu::GpuBuffer> UploadTransferFunction(const gpu::GpuContext& context,
                                              const TransferFunction& tf);

class TransferFunctionGpu {
 public:
  static Result<TransferFunctionGpu> Create(const gpu::GpuContext& context);

  // `tf_block`: a uniform buffer holding MakeTransferFunctionBlock(tf);
  // `out`: storage buffer of nx*ny*nz floats (cost, x fastest).
  Status Record(gpu::ComputeBatch& batch, const GpuVolume& volume, const gpu::GpuBuffer& tf_block,
                const gpu::GpuBuffer& out) const;

  Result<std::vector<float>> Run(const GpuVolume& volume, const TransferFunction& tf,
                                 double* gpu_ms = nullptr) const;

 private:
  TransferFunctionGpu(const gpu::GpuContext& context, gpu::ComputeKernel kernel)
      : context_(&context), kernel_(std::move(kernel)) {}
  const gpu::GpuContext* context_;
  gpu::ComputeKernel kernel_;
};

}  // namespace vpm

#include "server/volume/transfer_function_gpu.h"

#include "shaders/transfer_function.spv.h"

namespace vpm {

Result<gpu::TransferFunctionBlock> MakeTransferFunctionBlock(const TransferFunction& tf) {
  const auto& points = tf.points();
  if (points.size() > gpu::kMaxTfPoints) {
    return absl::InvalidArgumentError(StrCat("transfer function has ", points.size(),
                                                   " points; the GPU takes at most ",
                                                   gpu::kMaxTfPoints));
  }
  gpu::TransferFunctionBlock block{};
  for (size_t i = 0; i < points.size(); ++i) {
    // z: slope (cost per value unit) of the segment ending at point i,
    // computed once here in double instead of a divide per voxel and
    // segment in the shader; 0 for i = 0 and for steps (zero width).
    double slope = 0.0;
    if (i > 0 && points[i].value > points[i - 1].value) {
      slope = (points[i].cost - points[i - 1].cost) / (points[i].value - points[i - 1].value);
    }
    block.points[i] =
        glm::vec4(float(points[i].value), float(points[i].cost), float(slope), 0.0f);
  }
  block.count = glm::ivec4(static_cast<int>(points.size()), 0, 0, 0);
  return block;
}

Result<gpu::GpuBuffer> UploadTransferFunction(const gpu::GpuContext& context,
                                              const TransferFunction& tf) {
  ASSIGN_OR_RETURN(const gpu::TransferFunctionBlock block, MakeTransferFunctionBlock(tf));
  ASSIGN_OR_RETURN(gpu::GpuBuffer ubo,
                   gpu::GpuBuffer::Create(context, sizeof(block),
                                          vk::BufferUsageFlagBits::eUniformBuffer));
  RETURN_IF_ERROR(ubo.Upload(std::as_bytes(std::span(&block, 1))));
  return ubo;
}

Result<TransferFunctionGpu> TransferFunctionGpu::Create(const gpu::GpuContext& context) {
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = "transfer_function",
                                 .spirv = kTransferFunctionSpv,
                                 .bindings = {vk::DescriptorType::eUniformTexelBuffer,
                                              vk::DescriptorType::eUniformBuffer,
                                              vk::DescriptorType::eStorageBuffer},
                                 .push_constant_bytes = sizeof(gpu::VoxelMapPush),
                                 .local_size = {64, 1, 1}}));
  return TransferFunctionGpu(context, std::move(kernel));
}

Status TransferFunctionGpu::Record(gpu::ComputeBatch& batch, const GpuVolume& volume,
                                   const gpu::GpuBuffer& tf_block,
                                   const gpu::GpuBuffer& out) const {
  const auto e = volume.extent();
  const uint64_t bytes = uint64_t{e[0]} * e[1] * e[2] * sizeof(float);
  if (out.size_bytes() < bytes || tf_block.size_bytes() < sizeof(gpu::TransferFunctionBlock)) {
    return absl::InvalidArgumentError("transfer function buffers too small for the volume");
  }
  gpu::VoxelMapPush push{.dims = glm::ivec4(e[0], e[1], e[2], 0)};
  ASSIGN_OR_RETURN(const gpu::ComputeKernel kernel, volume.KernelFor(*context_, kernel_));
  return batch.Dispatch(kernel, {volume.texel_view(), &tf_block, &out}, push,
                        kernel.GroupsFor(e), "transfer_function");
}

Result<std::vector<float>> TransferFunctionGpu::Run(const GpuVolume& volume,
                                                    const TransferFunction& tf,
                                                    double* gpu_ms) const {
  const auto e = volume.extent();
  std::vector<float> result(size_t{e[0]} * e[1] * e[2]);
  ASSIGN_OR_RETURN(gpu::GpuBuffer ubo, UploadTransferFunction(*context_, tf));
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, result.size() * sizeof(float),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 1));
  RETURN_IF_ERROR(Record(batch, volume, ubo, out));
  ASSIGN_OR_RETURN(auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) *gpu_ms = timings.front().gpu_ms;
  RETURN_IF_ERROR(out.DownloadSpan(std::span<float>(result)));
  return result;
}

}  // namespace vpm

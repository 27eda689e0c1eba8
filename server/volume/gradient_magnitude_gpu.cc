#include "server/volume/gradient_magnitude_gpu.h"

#include "server/gpu/shader_interface.h"
#include "shaders/gradient_magnitude.spv.h"

namespace vpm {

Result<GradientMagnitudeGpu> GradientMagnitudeGpu::Create(const gpu::GpuContext& context) {
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = "gradient_magnitude",
                                 .spirv = kGradientMagnitudeSpv,
                                 .bindings = {vk::DescriptorType::eUniformTexelBuffer,
                                              vk::DescriptorType::eStorageBuffer},
                                 .push_constant_bytes = sizeof(gpu::GradientPush),
                                 .local_size = {64, 1, 1}}));
  return GradientMagnitudeGpu(context, std::move(kernel));
}

Status GradientMagnitudeGpu::Record(gpu::ComputeBatch& batch, const GpuVolume& volume,
                                    const gpu::GpuBuffer& out) const {
  const auto e = volume.extent();
  const uint64_t bytes = uint64_t{e[0]} * e[1] * e[2] * sizeof(float);
  if (out.size_bytes() < bytes) {
    return absl::InvalidArgumentError(StrCat("gradient output buffer holds ",
                                                   out.size_bytes(), " bytes, needs ", bytes));
  }
  const glm::dvec3& s = volume.geometry().spacing_mm;
  gpu::GradientPush push{
      .dims = glm::ivec4(e[0], e[1], e[2], 0),
      .inv_two_spacing = glm::vec4(float(1.0 / (2.0 * s.x)), float(1.0 / (2.0 * s.y)),
                                   float(1.0 / (2.0 * s.z)), 0.0f)};
  ASSIGN_OR_RETURN(const gpu::ComputeKernel kernel, volume.KernelFor(*context_, kernel_));
  return batch.Dispatch(kernel, {volume.texel_view(), &out}, push, kernel.GroupsFor(e),
                        "gradient_magnitude");
}

Result<std::vector<float>> GradientMagnitudeGpu::Run(const GpuVolume& volume,
                                                     double* gpu_ms) const {
  const auto e = volume.extent();
  std::vector<float> result(size_t{e[0]} * e[1] * e[2]);
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, result.size() * sizeof(float),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 1));
  RETURN_IF_ERROR(Record(batch, volume, out));
  ASSIGN_OR_RETURN(auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) *gpu_ms = timings.front().gpu_ms;
  RETURN_IF_ERROR(out.DownloadSpan(std::span<float>(result)));
  return result;
}

}  // namespace vpm

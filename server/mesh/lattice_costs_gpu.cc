#include "server/mesh/lattice_costs_gpu.h"

#include "server/gpu/compute_batch.h"
#include "server/gpu/shader_interface.h"
#include "server/volume/transfer_function_gpu.h"
#include "shaders/lattice_costs.spv.h"

namespace vpm {

Result<LatticeCostsGpu> LatticeCostsGpu::Create(const gpu::GpuContext& context) {
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = "lattice_costs",
                                 .spirv = kLatticeCostsSpv,
                                 .bindings = {vk::DescriptorType::eUniformTexelBuffer,
                                              vk::DescriptorType::eUniformBuffer,
                                              vk::DescriptorType::eStorageBuffer},
                                 .push_constant_bytes = sizeof(gpu::LatticeCostsPush),
                                 .local_size = {8, 8, 1}}));
  return LatticeCostsGpu(context, std::move(kernel));
}

Result<LatticeCosts> LatticeCostsGpu::Evaluate(const GpuVolume& volume, const Lattice& lattice,
                                               const TransferFunction& tf, double* gpu_ms) const {
  const auto& g = lattice.grid();
  if (volume.geometry().dims != lattice.geometry().dims) {
    return absl::InvalidArgumentError("lattice was built for a volume of other dimensions");
  }
  const size_t n = static_cast<size_t>(lattice.size());
  ASSIGN_OR_RETURN(gpu::GpuBuffer ubo, UploadTransferFunction(*context_, tf));
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, n * sizeof(glm::vec4),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  const auto& d = volume.geometry().dims;
  const glm::dvec3& s = volume.geometry().spacing_mm;
  const gpu::LatticeCostsPush push{
      .dims = glm::ivec4(d[0], d[1], d[2], 0),
      .grid = glm::ivec4(g[0], g[1], g[2], 0),
      .inv_two_spacing = glm::vec4(float(1.0 / (2.0 * s.x)), float(1.0 / (2.0 * s.y)),
                                   float(1.0 / (2.0 * s.z)), 0.0f)};
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 1));
  RETURN_IF_ERROR(batch.Dispatch(kernel_, {volume.texel_view(), &ubo, &out}, push,
                                 {uint32_t(g[0]), uint32_t(g[1]), uint32_t(g[2])}));
  ASSIGN_OR_RETURN(auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) *gpu_ms = timings.front().gpu_ms;
  std::vector<glm::vec4> raw(n);
  RETURN_IF_ERROR(out.DownloadSpan(std::span<glm::vec4>(raw)));
  LatticeCosts costs = LatticeCosts::Zeros(n);
  for (size_t i = 0; i < n; ++i) {
    costs.ci_cell[i] = raw[i].x;
    costs.g_cell[i] = raw[i].y;
    costs.ci_point[i] = raw[i].z;
    costs.g_point[i] = raw[i].w;
  }
  return costs;
}

}  // namespace vpm

#include "server/warp/warp_volume.h"

#include "server/gpu/shader_interface.h"
#include "shaders/warp_volume.spv.h"
#include "shaders/warp_volume_texel.spv.h"

namespace vpm {
namespace {

constexpr uint32_t kWarpLocalSize = 64;

}  // namespace

Result<VolumeWarper> VolumeWarper::Create(const gpu::GpuContext& context, const Options& options) {
  const bool sampler = options.source_read == SourceRead::kSampler;
  const auto source_binding =
      sampler ? vk::DescriptorType::eCombinedImageSampler : vk::DescriptorType::eUniformTexelBuffer;
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = sampler ? "warp_volume" : "warp_volume_texel",
                                 .spirv = sampler ? std::span<const uint32_t>(kWarpVolumeSpv)
                                                  : std::span<const uint32_t>(kWarpVolumeTexelSpv),
                                 .bindings = {vk::DescriptorType::eCombinedImageSampler,
                                              source_binding, vk::DescriptorType::eStorageBuffer},
                                 .push_constant_bytes = sizeof(gpu::WarpVolumePush),
                                 .local_size = {kWarpLocalSize, 1, 1}}));
  return VolumeWarper(context, options, std::move(kernel));
}

Status VolumeWarper::Record(gpu::ComputeBatch& batch, const GpuVolume& volume,
                            const gpu::GpuImage3D* source_image, const BackwardMap& map,
                            const gpu::GpuBuffer& out) const {
  const VolumeGeometry& g = volume.geometry();
  if (map.geometry().dims != g.dims || map.geometry().spacing_mm != g.spacing_mm) {
    return absl::InvalidArgumentError(
        "warp: the backward map belongs to a volume of other "
        "dims or spacing");
  }
  const auto e = volume.extent();
  const uint64_t bytes = uint64_t{e[0]} * e[1] * e[2] * sizeof(float);
  if (out.size_bytes() < bytes) {
    return absl::InvalidArgumentError(
        StrCat("warp: output buffer holds ", out.size_bytes(), " bytes, needs ", bytes));
  }
  const bool sampler = options_.source_read == SourceRead::kSampler;
  if (sampler && (source_image == nullptr || source_image->extent() != e)) {
    return absl::InvalidArgumentError("warp: the sampler path needs the volume's 3D image");
  }
  const glm::dvec3& s = g.spacing_mm;
  const auto& m = map.dims();
  const gpu::WarpVolumePush push{
      .dims = glm::ivec4(e[0], e[1], e[2], map.exact() ? 1 : 0),
      .inv_spacing = glm::vec4(glm::vec3(1.0 / s), 0.0f),
      .spacing_mm = glm::vec4(glm::vec3(s), 0.0f),
      .extent_mm = glm::vec4(glm::vec3(g.extent_mm()), 0.0f),
      .map_dims = glm::vec4(float(m[0]), float(m[1]), float(m[2]), 0.0f)};
  const gpu::KernelArg source =
      sampler ? gpu::KernelArg(source_image) : gpu::KernelArg(volume.texel_view());
  ASSIGN_OR_RETURN(const gpu::ComputeKernel kernel, volume.KernelFor(*context_, kernel_));
  return batch.Dispatch(kernel, {&map.image(), source, &out}, push, kernel.GroupsFor(e),
                        kernel.spec().name);
}

Result<Volume> VolumeWarper::Warp(GpuVolume& volume, const Volume& source, const BackwardMap& map,
                                  double* gpu_ms) const {
  if (source.geometry().dims != volume.geometry().dims) {
    return absl::InvalidArgumentError("warp: the host volume does not match the GPU volume");
  }
  const gpu::GpuImage3D* image = nullptr;
  if (options_.source_read == SourceRead::kSampler) {
    ASSIGN_OR_RETURN(image, volume.Image(*context_, source));
  }
  std::vector<float> values(static_cast<size_t>(source.geometry().voxel_count()));
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, values.size() * sizeof(float),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 1));
  RETURN_IF_ERROR(Record(batch, volume, image, map, out));
  ASSIGN_OR_RETURN(const auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) *gpu_ms = timings.front().gpu_ms;
  RETURN_IF_ERROR(out.DownloadSpan(std::span<float>(values)));
  // Float, whatever the source's encoding: interpolated values are not
  // integers. The source passed its budget; its warp is not capped again.
  ASSIGN_OR_RETURN(Volume warped, Volume::Create(source.geometry(), std::move(values),
                                                 UnboundedVolumeLimits()));
  warped.set_source(source.source() + " (warped)");
  return warped;
}

}  // namespace vpm

#include "server/volume/gpu_volume.h"

#include <algorithm>

namespace vpm {
namespace {

// Uploads go in slabs of this many bytes, so that a device without
// host-visible memory needs a staging buffer of one slab, not of the volume.
constexpr int64_t kUploadSlabBytes = int64_t{64} << 20;


}  // namespace

Result<GpuVolume> GpuVolume::Upload(const gpu::GpuContext& context, const Volume& volume,
                                    const ProgressFn& progress) {
  const uint64_t voxels = static_cast<uint64_t>(volume.geometry().voxel_count());
  const uint64_t per_texel = VoxelsPerTexel(volume.encoding());
  const uint64_t texels = (voxels + per_texel - 1) / per_texel;
  const uint64_t max_texels = context.limits().maxTexelBufferElements;
  if (texels > max_texels) {
    return absl::ResourceExhaustedError(
        StrCat("volume of ", DescribeVolumeSize(volume.geometry(), volume.encoding()), " needs ",
               texels, " texels of ", per_texel,
               " voxel(s), over this device's texel-buffer limit of ", max_texels, " (",
               max_texels * per_texel, " ", VoxelEncodingName(volume.encoding()), " voxels)"));
  }
  const vk::Format format = vk::Format::eR32Sint;
  const auto features = context.physical_device().getFormatProperties(format).bufferFeatures;
  if (!(features & vk::FormatFeatureFlagBits::eUniformTexelBuffer)) {
    return absl::FailedPreconditionError(StrCat("this device cannot read ", vk::to_string(format),
                                                " texel buffers (a Vulkan mandatory format)"));
  }
  constexpr uint64_t texel_bytes = 4;
  ASSIGN_OR_RETURN(gpu::GpuBuffer buffer,
                   gpu::GpuBuffer::Create(context, texels * texel_bytes,
                                          vk::BufferUsageFlagBits::eUniformTexelBuffer));
  const std::span<const std::byte> bytes = volume.voxels().bytes();
  for (size_t offset = 0; offset < bytes.size(); offset += kUploadSlabBytes) {
    const size_t n = std::min<size_t>(kUploadSlabBytes, bytes.size() - offset);
    RETURN_IF_ERROR(buffer.Upload(bytes.subspan(offset, n), offset));
    if (progress) progress(double(offset + n) / double(bytes.size()), "uploading");
  }
  // An odd int16 count leaves the last texel's high half unset: never read.
  vk::raii::BufferView view{nullptr};
  RETURN_IF_ERROR(gpu::CatchVulkan("creating the volume's texel view", [&] {
    view = vk::raii::BufferView(context.device(),
                                vk::BufferViewCreateInfo({}, buffer.handle(), format, 0,
                                                         texels * texel_bytes));
  }));
  return GpuVolume(std::move(buffer), std::move(view), volume);
}

Result<const gpu::GpuImage3D*> GpuVolume::Image(const gpu::GpuContext& context,
                                                const Volume& volume) {
  if (image_) return &*image_;
  if (volume.encoding() != encoding_ || volume.geometry().voxel_count() !=
                                            geometry_.voxel_count()) {
    return absl::InvalidArgumentError("GpuVolume::Image: not the volume that was uploaded");
  }
  if (encoding_ == VoxelEncoding::kFloat32) {
    ASSIGN_OR_RETURN(gpu::GpuImage3D image,
                     gpu::GpuImage3D::Create(context, extent(), vk::Format::eR32Sfloat));
    RETURN_IF_ERROR(image.Upload(volume.voxels().bytes()));
    image_.emplace(std::move(image));
    return &*image_;
  }
  // int16: R16_UNORM of stored + 32768 (flipping the sign bit), a format
  // with linear filtering on lavapipe and desktop GPUs (checked).
  const vk::Format format = vk::Format::eR16Unorm;
  const auto features = context.physical_device().getFormatProperties(format).optimalTilingFeatures;
  if (!(features & vk::FormatFeatureFlagBits::eSampledImageFilterLinear)) {
    return absl::FailedPreconditionError(
        "this device cannot filter R16_UNORM 3D images; use the texel-buffer kernels");
  }
  ASSIGN_OR_RETURN(gpu::GpuImage3D image, gpu::GpuImage3D::Create(context, extent(), format));
  const std::span<const int16_t> stored = volume.voxels().int16s();
  std::vector<uint16_t> shifted(stored.size());
  std::transform(stored.begin(), stored.end(), shifted.begin(),
                 [](int16_t s) { return static_cast<uint16_t>(static_cast<uint16_t>(s) ^ 0x8000u); });
  RETURN_IF_ERROR(image.Upload(std::as_bytes(std::span<const uint16_t>(shifted))));
  image_.emplace(std::move(image));
  return &*image_;
}

gpu::KernelSpec GpuVolume::Specialize(gpu::KernelSpec spec) const {
  if (spec.specialization.size() < 3) spec.specialization.resize(3, 0);
  spec.specialization[1] = encoding_ == VoxelEncoding::kInt16 ? 1u : 0u;
  spec.specialization[2] = static_cast<uint32_t>(offset_);
  return spec;
}

Result<gpu::ComputeKernel> GpuVolume::KernelFor(const gpu::GpuContext& context,
                                                const gpu::ComputeKernel& base) const {
  return gpu::ComputeKernel::Create(context, Specialize(base.spec()));
}

}  // namespace vpm

#include "server/volume/gpu_volume.h"

namespace vpm {

Result<GpuVolume> GpuVolume::Upload(const gpu::GpuContext& context, const Volume& volume) {
  const uint64_t texels = static_cast<uint64_t>(volume.geometry().voxel_count());
  if (texels > context.limits().maxTexelBufferElements) {
    return absl::ResourceExhaustedError(
        StrCat("volume of ", texels, " voxels exceeds this device's texel-buffer limit of ",
               context.limits().maxTexelBufferElements, " elements"));
  }
  ASSIGN_OR_RETURN(gpu::GpuBuffer buffer,
                   gpu::GpuBuffer::Create(context, texels * sizeof(float),
                                          vk::BufferUsageFlagBits::eUniformTexelBuffer));
  RETURN_IF_ERROR(buffer.Upload(std::as_bytes(volume.values())));
  vk::raii::BufferView view{nullptr};
  RETURN_IF_ERROR(gpu::CatchVulkan("creating the volume's texel view", [&] {
    view = vk::raii::BufferView(
        context.device(),
        vk::BufferViewCreateInfo({}, buffer.handle(), vk::Format::eR32Sfloat, 0, VK_WHOLE_SIZE));
  }));
  return GpuVolume(std::move(buffer), std::move(view), volume.geometry());
}

Result<const gpu::GpuImage3D*> GpuVolume::Image(const gpu::GpuContext& context,
                                                const Volume& volume) {
  if (!image_) {
    ASSIGN_OR_RETURN(gpu::GpuImage3D image,
                     gpu::GpuImage3D::Create(context, extent(), vk::Format::eR32Sfloat));
    RETURN_IF_ERROR(image.Upload(std::as_bytes(volume.values())));
    image_.emplace(std::move(image));
  }
  return &*image_;
}

}  // namespace vpm

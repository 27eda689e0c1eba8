#include "server/volume/gpu_volume.h"

namespace vpm {

Result<GpuVolume> GpuVolume::Upload(const gpu::GpuContext& context, const Volume& volume) {
  const auto& d = volume.dims();
  ASSIGN_OR_RETURN(
      gpu::GpuImage3D image,
      gpu::GpuImage3D::Create(context,
                              {static_cast<uint32_t>(d[0]), static_cast<uint32_t>(d[1]),
                               static_cast<uint32_t>(d[2])},
                              vk::Format::eR32Sfloat));
  RETURN_IF_ERROR(image.Upload(std::as_bytes(volume.values())));
  return GpuVolume(std::move(image), volume.geometry());
}

}  // namespace vpm

// A volume resident on the GPU: its values in an R32F 3D image (one texel per
// voxel, read with texelFetch or the trilinear sampler) plus its geometry.
#pragma once

#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/volume/volume.h"

namespace vpm {

class GpuVolume {
 public:
  static Result<GpuVolume> Upload(const gpu::GpuContext& context, const Volume& volume);

  const gpu::GpuImage3D& image() const { return image_; }
  const VolumeGeometry& geometry() const { return geometry_; }
  std::array<uint32_t, 3> extent() const { return image_.extent(); }

 private:
  GpuVolume(gpu::GpuImage3D image, VolumeGeometry geometry)
      : image_(std::move(image)), geometry_(geometry) {}
  gpu::GpuImage3D image_;
  VolumeGeometry geometry_;
};

}  // namespace vpm

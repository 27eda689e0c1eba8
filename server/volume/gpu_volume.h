// A volume resident on the GPU, plus its geometry. Its values (R32F, one
// texel per voxel, x fastest) live in a uniform texel buffer, which the
// per-voxel kernels read about twice as fast as a 3D image on lavapipe
// (docs/LAVAPIPE.md); the 3D image with its trilinear sampler is made on
// first request, for the kernels that want hardware filtering.
#pragma once

#include <optional>

#include "server/common/status.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/volume/volume.h"

namespace vpm {

class GpuVolume {
 public:
  static Result<GpuVolume> Upload(const gpu::GpuContext& context, const Volume& volume);

  // The values as a uniform texel buffer (R32F), for `uniform samplerBuffer`.
  vk::BufferView texel_view() const { return *view_; }
  const gpu::GpuBuffer& buffer() const { return buffer_; }
  // The values as a 3D image (R32F) with a trilinear sampler; uploaded on the
  // first call from the same host values.
  Result<const gpu::GpuImage3D*> Image(const gpu::GpuContext& context, const Volume& volume);
  const VolumeGeometry& geometry() const { return geometry_; }
  std::array<uint32_t, 3> extent() const {
    return {uint32_t(geometry_.dims[0]), uint32_t(geometry_.dims[1]), uint32_t(geometry_.dims[2])};
  }

 private:
  GpuVolume(gpu::GpuBuffer buffer, vk::raii::BufferView view, VolumeGeometry geometry)
      : buffer_(std::move(buffer)), view_(std::move(view)), geometry_(geometry) {}
  gpu::GpuBuffer buffer_;
  vk::raii::BufferView view_;  // declared after the buffer it views
  std::optional<gpu::GpuImage3D> image_;
  VolumeGeometry geometry_;
};

}  // namespace vpm

// A volume resident on the GPU, plus its geometry. Its values stay as the
// host holds them (server/volume/voxel_values.h: int16 + offset, or float)
// in a uniform texel buffer of R32_SINT texels, x fastest: 2 int16 voxels
// per texel (2 bytes per voxel), or one float's bits. Kernels read it as
// `uniform isamplerBuffer` through shaders/volume_access.glsl, specialized
// for the encoding (Specialize): a uniform texel buffer reads about twice as
// fast as a 3D image or a storage buffer on lavapipe (docs/LAVAPIPE.md), and
// 2 int16 voxels per texel keep a 512 x 512 x 1,024 CT (2^28 voxels) within
// the limit of 2^27 texels that lavapipe and NVIDIA's drivers set
// (maxTexelBufferElements; checked at upload). The default budget of
// 512 MiB (volume.h) fits that limit in both encodings: 2^28 int16 or 2^27
// float voxels.
// The 3D image with its trilinear sampler is made on first request, for the
// kernels that want hardware filtering (R16_UNORM of stored + 32768 for
// int16, R32F for float; shaders/voxel_encoding.glsl decodes both).
#pragma once

#include <optional>

#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/volume/volume.h"

namespace vpm {

class GpuVolume {
 public:
  // Voxels per R32_SINT texel of the texel buffer: 2 for int16, 1 for float.
  static int64_t VoxelsPerTexel(VoxelEncoding encoding) {
    return encoding == VoxelEncoding::kInt16 ? 2 : 1;
  }

  // ResourceExhausted when the volume needs more texels than the device's
  // maxTexelBufferElements; FailedPrecondition when the device lacks the
  // texel format. `progress` hears the fraction uploaded ("uploading").
  static Result<GpuVolume> Upload(const gpu::GpuContext& context, const Volume& volume,
                                  const ProgressFn& progress = {});

  // The values as a uniform texel buffer, for `uniform isamplerBuffer`.
  vk::BufferView texel_view() const { return *view_; }
  const gpu::GpuBuffer& buffer() const { return buffer_; }
  // The values as a 3D image with a trilinear sampler; uploaded on the first
  // call from the same host values.
  Result<const gpu::GpuImage3D*> Image(const gpu::GpuContext& context, const Volume& volume);
  const VolumeGeometry& geometry() const { return geometry_; }
  std::array<uint32_t, 3> extent() const {
    return {uint32_t(geometry_.dims[0]), uint32_t(geometry_.dims[1]), uint32_t(geometry_.dims[2])};
  }
  VoxelEncoding encoding() const { return encoding_; }
  int32_t int16_offset() const { return offset_; }
  // Device bytes of the texel buffer (the 3D image, if made, comes on top).
  int64_t buffer_bytes() const { return static_cast<int64_t>(buffer_.size_bytes()); }

  // `spec` with specialization constants 1 and 2 set to this volume's
  // encoding and offset (shaders/voxel_encoding.glsl); constant 0 kept.
  gpu::KernelSpec Specialize(gpu::KernelSpec spec) const;
  // The kernel of `base`'s spec specialized for this volume (from the
  // context's pipeline cache after the first call).
  Result<gpu::ComputeKernel> KernelFor(const gpu::GpuContext& context,
                                       const gpu::ComputeKernel& base) const;

 private:
  GpuVolume(gpu::GpuBuffer buffer, vk::raii::BufferView view, const Volume& volume)
      : buffer_(std::move(buffer)),
        view_(std::move(view)),
        geometry_(volume.geometry()),
        encoding_(volume.encoding()),
        offset_(volume.voxels().int16_offset()) {}
  gpu::GpuBuffer buffer_;
  vk::raii::BufferView view_;  // declared after the buffer it views
  std::optional<gpu::GpuImage3D> image_;
  VolumeGeometry geometry_;
  VoxelEncoding encoding_;
  int32_t offset_;
};

}  // namespace vpm

// A volume resident on the GPU, plus its geometry. Its values stay as the
// host holds them (server/volume/voxel_values.h: int16 + offset, or float)
// in a uniform texel buffer, x fastest, in one of two layouts (TexelLayout):
//   pairs: texel n holds voxels n and n + 1 (int16: one R32_SINT texel, n in
//     the low half; float: one R32G32_SINT texel of both floats' bits), so
//     that a trilinear read fetches the 4 texels of a cell's x-edges instead
//     of its 8 voxels: the ray caster's stills cost 5-15% less on lavapipe
//     (docs/LAVAPIPE.md, "Volumes through uniform texel buffers"), for
//     twice the host's bytes;
//   packed (int16 over the limit below): texel t holds voxels 2t and 2t + 1,
//     2 bytes per voxel, so that a 512 x 512 x 1,024 CT (2^28 voxels) stays
//     within the limit of 2^27 texels that lavapipe and NVIDIA's drivers set
//     (maxTexelBufferElements; checked at upload).
// Kernels read it as `uniform isamplerBuffer` through
// shaders/volume_access.glsl, specialized for the encoding and the layout
// (Specialize): a uniform texel buffer reads about twice as fast as a 3D
// image or a storage buffer on lavapipe (docs/LAVAPIPE.md). The default
// budget of 512 MiB (volume.h) fits the limit: 2^28 int16 voxels (packed)
// or 2^27 float voxels (pairs, 1 GiB on the device).
// The 3D image with its trilinear sampler is made on first request, for the
// kernels that want hardware filtering (R16_UNORM of stored + 32768 for
// int16, R32F for float; shaders/voxel_encoding.glsl decodes both).
#pragma once

#include <optional>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/volume/volume.h"

namespace vpm {

class GpuVolume {
 public:
  enum class TexelLayout { kPairs, kPacked };

  // The layout a volume of `voxels` voxels gets under a limit of
  // `max_texels` texels: pairs where they fit, else packed (int16);
  // nullopt when neither fits (a float volume over the limit).
  static std::optional<TexelLayout> LayoutFor(VoxelEncoding encoding, uint64_t voxels,
                                              uint64_t max_texels);
  // Device bytes of the texel buffer Upload makes in LayoutFor's layout (0
  // when none fits): int16 4 per voxel in pairs, 2 packed; float 8.
  static uint64_t BufferBytesFor(VoxelEncoding encoding, uint64_t voxels, uint64_t max_texels);

  // ResourceExhausted when the volume needs more texels than the device's
  // maxTexelBufferElements; FailedPrecondition when the device lacks the
  // texel format. `progress` hears the fraction uploaded ("uploading").
  // `layout`: LayoutFor's unless given (tests: both layouts give the same
  // values; ResourceExhausted where the given one cannot hold the volume,
  // InvalidArgument for a float volume packed). `cancel` is polled between
  // slabs of kUploadSlabBytes (its status returned, nothing kept).
  static Result<GpuVolume> Upload(const gpu::GpuContext& context, const Volume& volume,
                                  const ProgressFn& progress = {},
                                  std::optional<TexelLayout> layout = std::nullopt,
                                  const CancelToken& cancel = {});

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
  TexelLayout layout() const { return layout_; }
  int32_t int16_offset() const { return offset_; }
  // Device bytes of the texel buffer (the 3D image, if made, comes on top).
  int64_t buffer_bytes() const { return static_cast<int64_t>(buffer_.size_bytes()); }

  // `spec` with specialization constants 1, 2 and 4 set to this volume's
  // encoding, offset and layout (shaders/voxel_encoding.glsl); constants 0
  // and 3 kept.
  gpu::KernelSpec Specialize(gpu::KernelSpec spec) const;
  // The kernel of `base`'s spec specialized for this volume (from the
  // context's pipeline cache after the first call).
  Result<gpu::ComputeKernel> KernelFor(const gpu::GpuContext& context,
                                       const gpu::ComputeKernel& base) const;

 private:
  GpuVolume(gpu::GpuBuffer buffer, vk::raii::BufferView view, const Volume& volume,
            TexelLayout layout)
      : buffer_(std::move(buffer)),
        view_(std::move(view)),
        geometry_(volume.geometry()),
        encoding_(volume.encoding()),
        layout_(layout),
        offset_(volume.voxels().int16_offset()) {}
  gpu::GpuBuffer buffer_;
  vk::raii::BufferView view_;  // declared after the buffer it views
  std::optional<gpu::GpuImage3D> image_;
  VolumeGeometry geometry_;
  VoxelEncoding encoding_;
  TexelLayout layout_;
  int32_t offset_;
};

}  // namespace vpm

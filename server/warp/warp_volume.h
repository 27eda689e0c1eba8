// The deformed volume J(x) = I(X(x)) of docs/ALGORITHM.md section 7 on the GPU:
// every voxel x = index * spacing of the source grid reads its rest position
// X(x) through a BackwardMap and the source trilinearly there (kernels
// shaders/warp_volume.comp and warp_volume_texel.comp). With a map of one
// point per voxel (BackwardMap::exact()) this is the exact warp, each voxel
// with its own tet lookup; with a coarser map the displacement between map
// points is trilinear (docs/WARP.md gives the error). CPU references:
// WarpVolumeCpu, WarpVolumeExactCpu.
#pragma once

#include "server/common/status.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_image3d.h"
#include "server/warp/backward_map.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/volume.h"

namespace vpm {

class VolumeWarper {
 public:
  // How the kernel reads the source volume. kTexelBuffer (the default): its
  // R32F texel buffer with a manual trilinear, the arithmetic of
  // SampleTrilinear, bit-exact at integer indices (the identity gives the
  // volume back exactly). kSampler: its 3D image (GpuVolume::Image, 4 more
  // bytes per voxel) with the hardware trilinear filter, which real GPUs
  // compute with 8-bit weights. On lavapipe both take the same time within
  // the noise (docs/WARP.md).
  enum class SourceRead { kTexelBuffer, kSampler };
  struct Options {
    SourceRead source_read = SourceRead::kTexelBuffer;
  };

  static Result<VolumeWarper> Create(const gpu::GpuContext& context, const Options& options);
  static Result<VolumeWarper> Create(const gpu::GpuContext& context) {
    return Create(context, Options{});
  }

  // Records the warp into `batch`: `out`, a storage buffer of at least
  // nx*ny*nz floats, receives J (x fastest, the source's grid).
  // `source_image`: the volume's 3D image (GpuVolume::Image) for kSampler;
  // ignored for kTexelBuffer. The map must belong to a volume of the same
  // dims and spacing.
  Status Record(gpu::ComputeBatch& batch, const GpuVolume& volume,
                const gpu::GpuImage3D* source_image, const BackwardMap& map,
                const gpu::GpuBuffer& out) const;

  // Runs the warp alone and returns J as a volume with the source's
  // geometry (origin and direction included, so WriteNifti exports it in
  // the source's world space); `source` is the host copy of `volume`.
  Result<Volume> Warp(GpuVolume& volume, const Volume& source, const BackwardMap& map,
                      double* gpu_ms = nullptr) const;

  SourceRead source_read() const { return options_.source_read; }

 private:
  VolumeWarper(const gpu::GpuContext& context, const Options& options, gpu::ComputeKernel kernel)
      : context_(&context), options_(options), kernel_(std::move(kernel)) {}
  const gpu::GpuContext* context_;
  Options options_;
  gpu::ComputeKernel kernel_;
};

}  // namespace vpm

// A slice of the deformed volume J(x) = I(X(x)) (docs/ALGORITHM.md section
// 7) on a SliceGrid: each pixel's physical point x reads its rest position
// X(x) = x + d(x) from the backward map (trilinear between map points, as
// shaders/backward_map.glsl) and the source trilinearly there (clamped
// indexing). Pixels whose point lies outside the image box read NaN.
// GPU: SliceSampler (shaders/slice_volume.comp); CPU reference:
// SampleSliceCpu, the same arithmetic in double.
#pragma once

#include <array>
#include <vector>

#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/raycast/slice_grid.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/volume.h"
#include "server/warp/backward_map_values.h"

namespace vpm {

// J per pixel, width * height floats, row 0 at the top; `map` null: at rest.
std::vector<float> SampleSliceCpu(const Volume& volume, const BackwardMapValues* map,
                                  const SliceGrid& grid);

class SliceSampler {
 public:
  static Result<SliceSampler> Create(const gpu::GpuContext& context);

  // `map_image`: the backward map (R32G32B32A32Sfloat, map_dims points
  // corner to corner of the box, BackwardMap::image()). Returns J per pixel
  // as SampleSliceCpu; `gpu_ms` (optional) gets the kernel's time.
  Result<std::vector<float>> Sample(const GpuVolume& volume, const gpu::GpuImage3D& map_image,
                                    const std::array<int64_t, 3>& map_dims, const SliceGrid& grid,
                                    double* gpu_ms = nullptr) const;

 private:
  SliceSampler(const gpu::GpuContext& context, gpu::ComputeKernel kernel)
      : context_(&context), kernel_(std::move(kernel)) {}
  const gpu::GpuContext* context_;
  gpu::ComputeKernel kernel_;
};

}  // namespace vpm

#include "server/raycast/slice_sampler.h"

#include <cmath>
#include <limits>

#include "server/gpu/compute_batch.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/shader_interface.h"
#include "server/volume/sample_trilinear.h"
#include "shaders/slice_volume.spv.h"

namespace vpm {
namespace {

constexpr uint32_t kLocalSize = 8;  // 8 x 8 pixels per workgroup

// Inside the image box [0, extent] with a margin of 1e-4 mm: float round-off
// at the box's faces must not turn a face pixel into NaN on one side only.
bool InsideBox(const glm::dvec3& p, const glm::dvec3& extent) {
  constexpr double kMargin = 1e-4;
  return p.x >= -kMargin && p.y >= -kMargin && p.z >= -kMargin && p.x <= extent.x + kMargin &&
         p.y <= extent.y + kMargin && p.z <= extent.z + kMargin;
}

}  // namespace

std::vector<float> SampleSliceCpu(const Volume& volume, const BackwardMapValues* map,
                                  const SliceGrid& grid) {
  const glm::dvec3 extent = volume.geometry().extent_mm();
  std::vector<float> out(size_t(grid.width) * grid.height);
  for (int j = 0; j < grid.height; ++j) {
    for (int i = 0; i < grid.width; ++i) {
      const glm::dvec3 x = grid.PixelCentreMm(i, j);
      float value = std::numeric_limits<float>::quiet_NaN();
      if (InsideBox(x, extent)) {
        const glm::dvec3 rest = map != nullptr ? x + glm::dvec3(map->Sample(x)) : x;
        value = float(SampleTrilinear(volume, rest));
      }
      out[size_t(j) * grid.width + i] = value;
    }
  }
  return out;
}

Result<SliceSampler> SliceSampler::Create(const gpu::GpuContext& context) {
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = "slice_volume",
                                 .spirv = std::span<const uint32_t>(kSliceVolumeSpv),
                                 .bindings = {vk::DescriptorType::eCombinedImageSampler,
                                              vk::DescriptorType::eUniformTexelBuffer,
                                              vk::DescriptorType::eStorageBuffer},
                                 .push_constant_bytes = sizeof(gpu::SliceVolumePush),
                                 .local_size = {kLocalSize, kLocalSize, 1}}));
  return SliceSampler(context, std::move(kernel));
}

Result<std::vector<float>> SliceSampler::Sample(const GpuVolume& volume,
                                                const gpu::GpuImage3D& map_image,
                                                const std::array<int64_t, 3>& map_dims,
                                                const SliceGrid& grid, double* gpu_ms) const {
  if (grid.width < 1 || grid.height < 1 || grid.width > kMaxSliceSide ||
      grid.height > kMaxSliceSide) {
    return absl::InvalidArgumentError(StrCat("slice of ", grid.width, "x", grid.height,
                                             " pixels: each side must be in 1..", kMaxSliceSide));
  }
  const auto& e = map_image.extent();
  if (map_dims[0] < 2 || map_dims[1] < 2 || map_dims[2] < 2 ||
      e != std::array<uint32_t, 3>{uint32_t(map_dims[0]), uint32_t(map_dims[1]),
                                   uint32_t(map_dims[2])} ||
      map_image.format() != vk::Format::eR32G32B32A32Sfloat) {
    return absl::InvalidArgumentError(
        "slice: the backward map must be an RGBA32F image of map_dims points, at least 2 a side");
  }
  const VolumeGeometry& g = volume.geometry();
  const std::size_t pixels = size_t(grid.width) * grid.height;
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, pixels * sizeof(float),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  const gpu::SliceVolumePush push{
      .dims = glm::ivec4(int(g.dims[0]), int(g.dims[1]), int(g.dims[2]), 0),
      .inv_spacing = glm::vec4(glm::vec3(1.0 / g.spacing_mm), 0.0f),
      .extent_mm = glm::vec4(glm::vec3(g.extent_mm()), 0.0f),
      .map_dims = glm::vec4(float(map_dims[0]), float(map_dims[1]), float(map_dims[2]), 0.0f),
      .origin_mm = glm::vec4(glm::vec3(grid.origin_mm), 0.0f),
      .step_u_mm = glm::vec4(glm::vec3(grid.step_u_mm), 0.0f),
      .step_v_mm = glm::vec4(glm::vec3(grid.step_v_mm), 0.0f),
      .image = glm::ivec4(grid.width, grid.height, 0, 0)};
  ASSIGN_OR_RETURN(const gpu::ComputeKernel kernel, volume.KernelFor(*context_, kernel_));
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 1));
  RETURN_IF_ERROR(batch.Dispatch(
      kernel, {&map_image, volume.texel_view(), &out}, push,
      kernel.GroupsFor({uint32_t(grid.width), uint32_t(grid.height), 1}), "slice_volume"));
  ASSIGN_OR_RETURN(const auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) *gpu_ms = timings.front().gpu_ms;
  std::vector<float> values(pixels);
  RETURN_IF_ERROR(out.DownloadSpan(std::span<float>(values)));
  return values;
}

}  // namespace vpm

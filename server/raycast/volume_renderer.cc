#include "server/raycast/volume_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "server/common/clock.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/dispatch_threads.h"
#include "server/gpu/shader_interface.h"
#include "shaders/brick_minmax.spv.h"
#include "shaders/brick_occupancy.spv.h"
#include "shaders/raycast_dvr.spv.h"
#include "shaders/raycast_dvr_map.spv.h"
#include "shaders/raycast_dvr_map_sampled.spv.h"
#include "shaders/raycast_dvr_sampled.spv.h"
#include "shaders/raycast_mip.spv.h"
#include "shaders/raycast_mip_map.spv.h"
#include "shaders/raycast_mip_map_sampled.spv.h"
#include "shaders/raycast_mip_sampled.spv.h"
#include "shaders/upscale.spv.h"

namespace vpm {
namespace {

using DT = vk::DescriptorType;
using BU = vk::BufferUsageFlagBits;

// Brick grids cached: 4 volumes at both brick sizes.
constexpr size_t kMaxCachedBrickGrids = 8;

uint32_t GroupCount(int threads, int local) { return uint32_t((threads + local - 1) / local); }

// Consecutive pixels of a row per invocation of upscale.comp.
constexpr int kUpscalePixelsPerInvocation = 4;

// The ray-casting variant for (access, mode, map): shaders/raycast_body.glsl.
std::span<const uint32_t> RaycastSpirv(bool sampled, bool mip, bool map) {
  if (sampled) {
    if (mip) return map ? std::span<const uint32_t>(kRaycastMipMapSampledSpv) : kRaycastMipSampledSpv;
    return map ? std::span<const uint32_t>(kRaycastDvrMapSampledSpv) : kRaycastDvrSampledSpv;
  }
  if (mip) return map ? std::span<const uint32_t>(kRaycastMipMapSpv) : kRaycastMipSpv;
  return map ? std::span<const uint32_t>(kRaycastDvrMapSpv) : kRaycastDvrSpv;
}

// A ray caster's kernel: DVR or MIP, with or without a backward map, and
// DVR shaded with the cell gradient (specialization constant
// kCellGradient), pre-integrated or not.
gpu::KernelSpec RaycastSpec(bool sampled, bool mip, bool map, bool cell_gradient,
                            bool preintegrated) {
  const DT volume_read = sampled ? DT::eCombinedImageSampler : DT::eUniformTexelBuffer;
  gpu::KernelSpec spec{
      .name =
          StrCat("raycast_", mip ? "mip" : "dvr", map ? "_map" : "", sampled ? "_sampled" : "",
                 cell_gradient ? " (cell gradient)" : "", preintegrated ? " (pre-integrated)" : ""),
      .spirv = RaycastSpirv(sampled, mip, map),
      .bindings = {volume_read, volume_read, DT::eStorageBuffer, DT::eUniformTexelBuffer,
                   DT::eUniformTexelBuffer, DT::eStorageBuffer, DT::eStorageBuffer},
      .push_constant_bytes = sizeof(gpu::RaycastBandPush),
      .local_size = {8, 8, 1}};
  // Ids 1, 2 and 4 are the volume's (GpuVolume::KernelFor), 3 pre-integration.
  if (cell_gradient) spec.specialization = {1u, 0u, 0u, preintegrated ? 1u : 0u};
  return spec;
}

// Band 0's ray cast (GPU timestamps) in the first submit's timings, else
// that submit's wall time.
double Band0Ms(std::span<const gpu::DispatchTiming> timings, double first_submit_ms) {
  for (const auto& t : timings) {
    if (t.label == "raycast") return t.gpu_ms >= 0.0 ? t.gpu_ms : first_submit_ms;
  }
  return first_submit_ms;
}

}  // namespace

Result<std::unique_ptr<VolumeRenderer>> VolumeRenderer::Create(const gpu::GpuContext& context,
                                                               const Options& options) {
  std::unique_ptr<VolumeRenderer> renderer(new VolumeRenderer(context, options));
  RETURN_IF_ERROR(renderer->Init());
  return renderer;
}

VolumeRenderer::VolumeRenderer(const gpu::GpuContext& context, const Options& options)
    : context_(&context), options_(options) {
  if (options_.dispatch_threads == 0) {
    options_.dispatch_threads = gpu::DispatchThreads(context.is_cpu_device());
  }
}

Status VolumeRenderer::Init() {
  RETURN_IF_ERROR(CreateKernels());
  return CreateBuffers();
}

Status VolumeRenderer::CreateKernels() {
  const bool sampled = options_.volume_access == VolumeAccess::kSampler3D;
  ASSIGN_OR_RETURN(auto minmax,
                   gpu::ComputeKernel::Create(
                       *context_, {.name = "brick_minmax",
                                   .spirv = kBrickMinmaxSpv,
                                   .bindings = {DT::eUniformTexelBuffer, DT::eStorageBuffer},
                                   .push_constant_bytes = sizeof(gpu::BrickMinMaxPush),
                                   .local_size = {64, 1, 1}}));
  ASSIGN_OR_RETURN(auto occupancy,
                   gpu::ComputeKernel::Create(
                       *context_, {.name = "brick_occupancy",
                                   .spirv = kBrickOccupancySpv,
                                   .bindings = {DT::eStorageBuffer, DT::eUniformTexelBuffer,
                                                DT::eStorageBuffer, DT::eStorageBuffer},
                                   .push_constant_bytes = sizeof(gpu::BrickOccupancyPush),
                                   .local_size = {64, 1, 1}}));
  for (int mip = 0; mip < 2; ++mip) {
    for (int map = 0; map < 2; ++map) {
      ASSIGN_OR_RETURN(auto raycast, gpu::ComputeKernel::Create(
                                         *context_, RaycastSpec(sampled, mip, map, false, false)));
      raycast_kernels_[mip][map].emplace(std::move(raycast));
    }
  }
  for (int map = 0; map < 2; ++map) {
    ASSIGN_OR_RETURN(auto raycast, gpu::ComputeKernel::Create(
                                       *context_, RaycastSpec(sampled, false, map, true, false)));
    cell_gradient_kernels_[map].emplace(std::move(raycast));
    ASSIGN_OR_RETURN(
        auto preintegrated,
        gpu::ComputeKernel::Create(*context_, RaycastSpec(sampled, false, map, true, true)));
    preintegrated_kernels_[map].emplace(std::move(preintegrated));
  }
  ASSIGN_OR_RETURN(auto upscale,
                   gpu::ComputeKernel::Create(
                       *context_, {.name = "upscale",
                                   .spirv = kUpscaleSpv,
                                   .bindings = {DT::eStorageBuffer, DT::eStorageBuffer},
                                   .push_constant_bytes = sizeof(gpu::UpscalePush),
                                   .local_size = {8, 8, 1}}));
  minmax_kernel_.emplace(std::move(minmax));
  occupancy_kernel_.emplace(std::move(occupancy));
  upscale_kernel_.emplace(std::move(upscale));
  return absl::OkStatus();
}

Status VolumeRenderer::CreateBuffers() {
  ASSIGN_OR_RETURN(auto identity, gpu::GpuImage3D::Create(*context_, {2, 2, 2},
                                                          vk::Format::eR32G32B32A32Sfloat));
  const std::vector<glm::vec4> zeros(8, glm::vec4(0.0f));
  RETURN_IF_ERROR(identity.Upload(std::as_bytes(std::span<const glm::vec4>(zeros))));
  identity_map_.emplace(std::move(identity));
  // Params are a storage buffer (shaders/raycast_body.glsl says why).
  RETURN_IF_ERROR(EnsureBuffer(params_, sizeof(gpu::RaycastParams), BU::eStorageBuffer));
  RETURN_IF_ERROR(
      EnsureBuffer(lut_,
                   sizeof(gpu::RenderLutBlock) + sizeof(glm::vec4) * gpu::kPreintegratedEntries *
                                                     gpu::kPreintegratedEntries,
                   BU::eUniformTexelBuffer));
  RETURN_IF_ERROR(gpu::CatchVulkan("creating the lookup table's texel view", [&] {
    lut_view_ = vk::raii::BufferView(
        context_->device(), vk::BufferViewCreateInfo({}, lut_->handle(),
                                                     vk::Format::eR32G32B32A32Sfloat, 0,
                                                     VK_WHOLE_SIZE));
  }));
  RETURN_IF_ERROR(EnsureBuffer(nonzero_prefix_, (gpu::kRenderLutEntries + 1) * sizeof(int32_t),
                               BU::eStorageBuffer));
  RETURN_IF_ERROR(EnsureBuffer(stats_, 16, BU::eStorageBuffer));
  return EnsureMapTexels(8);
}

Status VolumeRenderer::EnsureMapTexels(size_t points) {
  if (map_texels_ && map_texels_->size_bytes() >= points * sizeof(glm::vec4)) {
    return absl::OkStatus();
  }
  if (points > context_->limits().maxTexelBufferElements) {
    return absl::ResourceExhaustedError(
        StrCat("backward map of ", points, " points exceeds this device's texel-buffer limit of ",
               context_->limits().maxTexelBufferElements, "; use VolumeAccess::kSampler3D"));
  }
  map_texels_view_ = nullptr;
  map_texels_.reset();
  ASSIGN_OR_RETURN(auto buffer, gpu::GpuBuffer::Create(*context_, points * sizeof(glm::vec4),
                                                       BU::eStorageBuffer |
                                                           BU::eUniformTexelBuffer |
                                                           BU::eTransferDst));
  map_texels_.emplace(std::move(buffer));
  return gpu::CatchVulkan("creating the backward map's texel view", [&] {
    map_texels_view_ = vk::raii::BufferView(
        context_->device(), vk::BufferViewCreateInfo({}, map_texels_->handle(),
                                                     vk::Format::eR32G32B32A32Sfloat, 0,
                                                     VK_WHOLE_SIZE));
  });
}

Status VolumeRenderer::EnsureOccupancy(size_t bricks) {
  if (occupancy_ && occupancy_->size_bytes() >= bricks * sizeof(float)) return absl::OkStatus();
  occupancy_key_.reset();
  occupancy_view_ = nullptr;
  occupancy_.reset();
  RETURN_IF_ERROR(EnsureBuffer(occupancy_, bricks * sizeof(float),
                               BU::eStorageBuffer | BU::eUniformTexelBuffer));
  return gpu::CatchVulkan("creating the occupancy's texel view", [&] {
    occupancy_view_ = vk::raii::BufferView(
        context_->device(), vk::BufferViewCreateInfo({}, occupancy_->handle(),
                                                     vk::Format::eR32Sfloat, 0, VK_WHOLE_SIZE));
  });
}

Status VolumeRenderer::EnsureBuffer(std::optional<gpu::GpuBuffer>& buffer, vk::DeviceSize bytes,
                                    vk::BufferUsageFlags usage) {
  if (buffer && buffer->size_bytes() >= bytes) return absl::OkStatus();
  buffer.reset();
  ASSIGN_OR_RETURN(auto created, gpu::GpuBuffer::Create(*context_, bytes, usage));
  buffer.emplace(std::move(created));
  return absl::OkStatus();
}

void VolumeRenderer::ForgetVolume(const GpuVolume* volume) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::erase_if(brick_grids_, [&](const BrickGrid& g) { return g.volume == volume; });
  if (occupancy_key_ && occupancy_key_->volume == volume) occupancy_key_.reset();
}

Result<const gpu::GpuBuffer*> VolumeRenderer::BrickMinMax(const GpuVolume& volume,
                                                          glm::ivec3 brick_voxels) {
  const vk::Buffer handle = volume.buffer().handle();
  for (auto it = brick_grids_.begin(); it != brick_grids_.end(); ++it) {
    if (it->volume == &volume && it->brick_voxels == brick_voxels) {
      if (it->buffer == handle && it->extent == volume.extent()) return &it->minmax;
      brick_grids_.erase(it);
      break;
    }
  }
  const auto& g = volume.geometry();
  const auto nb = BrickGridDims(g.dims, brick_voxels);
  const int bricks = nb[0] * nb[1] * nb[2];
  ASSIGN_OR_RETURN(auto minmax, gpu::GpuBuffer::Create(*context_, bricks * sizeof(glm::vec2),
                                                       BU::eStorageBuffer));
  ASSIGN_OR_RETURN(auto batch, gpu::ComputeBatch::Begin(*context_, 1));
  const gpu::BrickMinMaxPush push{
      .dims = glm::ivec4(int(g.dims[0]), int(g.dims[1]), int(g.dims[2]), 0),
      .bricks = glm::ivec4(nb[0], nb[1], nb[2], 0),
      .brick_voxels = glm::ivec4(brick_voxels, 0)};
  ASSIGN_OR_RETURN(const gpu::ComputeKernel kernel, volume.KernelFor(*context_, *minmax_kernel_));
  RETURN_IF_ERROR(batch.Dispatch(kernel, {volume.texel_view(), &minmax}, push,
                                 {GroupCount(bricks, 64), 1, 1}, "brick_minmax"));
  RETURN_IF_ERROR(batch.SubmitAndWait().status());
  if (brick_grids_.size() >= kMaxCachedBrickGrids) brick_grids_.erase(brick_grids_.begin());
  brick_grids_.push_back({&volume, brick_voxels, handle, volume.extent(), std::move(minmax)});
  return &brick_grids_.back().minmax;
}

Status VolumeRenderer::PrepareLut(const RenderPreset& preset, double step_mm,
                                  bool preintegrated) {
  const bool same = lut_preset_ && *lut_preset_ == preset && lut_step_mm_ == step_mm;
  if (same && (!preintegrated || preintegrated_baked_)) return absl::OkStatus();
  if (preintegrated) {
    // After the RenderLutBlock in the same buffer (shader_interface.h).
    const std::vector<glm::vec4>& table = preintegrated_tables_.Table(preset, step_mm);
    RETURN_IF_ERROR(lut_->Upload(std::as_bytes(std::span<const glm::vec4>(table)),
                                 sizeof(gpu::RenderLutBlock)));
  }
  preintegrated_baked_ = preintegrated;
  if (same) return absl::OkStatus();
  const RenderLut lut = BakeRenderLut(preset, step_mm);
  RETURN_IF_ERROR(lut_->Upload(std::as_bytes(std::span<const glm::vec4>(lut.entries))));
  RETURN_IF_ERROR(
      nonzero_prefix_->Upload(std::as_bytes(std::span<const int32_t>(lut.nonzero_prefix))));
  lut_preset_ = preset;
  lut_step_mm_ = step_mm;
  ++lut_generation_;
  lut_params_ = LutParams(lut);
  return absl::OkStatus();
}

Status VolumeRenderer::CheckGpuInputs(const RenderRequest& request) const {
  if (request.volume == nullptr) {
    return absl::InvalidArgumentError("render request has no volume");
  }
  if (options_.volume_access == VolumeAccess::kSampler3D) {
    const gpu::GpuImage3D* image = request.volume_image;
    if (image == nullptr || image->extent() != request.volume->extent()) {
      return absl::InvalidArgumentError(
          "this renderer samples a 3D image: the request needs volume_image "
          "(GpuVolume::Image) of the volume's extent");
    }
  }
  if (const gpu::GpuImage3D* map = request.backward_map) {
    const auto& e = map->extent();
    if (map->format() != vk::Format::eR32G32B32A32Sfloat || e[0] < 2 || e[1] < 2 || e[2] < 2) {
      return absl::InvalidArgumentError(
          "backward map must be an R32G32B32A32Sfloat 3D image of at least 2^3 points");
    }
  }
  return absl::OkStatus();
}

// Per axis a brick reads the
// points of the map cells it overlaps, floor(its lowest voxel's mm * to_grid)
// .. floor(its highest's) + 1, computed as the kernel does but in double and
// widened by a point each way, so that float rounding cannot leave a brick
// out (an extra brick gets the same occupancy again).
VolumeRenderer::BrickBox VolumeRenderer::BricksMeetingMapBox(const gpu::RaycastParams& p,
                                                             const std::array<int, 3>& map_dims,
                                                             const glm::ivec3& lo,
                                                             const glm::ivec3& hi) {
  BrickBox box;
  for (int a = 0; a < 3; ++a) {
    const int n = p.dims[a], w = p.brick_voxels[a], m = map_dims[a];
    const double s = p.spacing_mm[a];
    const double to_grid = double(m - 1) / (double(std::max(n - 1, 1)) * s);
    int first = p.bricks[a], last = -1;
    for (int b = 0; b < p.bricks[a]; ++b) {
      const double lo_mm = double(b * w) * s;
      const double hi_mm = double(std::min((b + 1) * w, n - 1)) * s;
      const int g_lo = std::clamp(int(std::floor(lo_mm * to_grid)), 0, m - 1);
      const int g_hi = std::clamp(int(std::floor(hi_mm * to_grid)) + 1, 0, m - 1);
      if (g_lo <= hi[a] + 1 && g_hi >= lo[a] - 1) {
        first = std::min(first, b);
        last = b;
      }
    }
    if (last < first) return {};
    box.lo[a] = first;
    box.size[a] = last - first + 1;
  }
  return box;
}

Status VolumeRenderer::RecordFrame(gpu::ComputeBatch& batch, const RenderRequest& request,
                                   const RaycastSetup& setup, const gpu::GpuBuffer& minmax,
                                   bool upscale, const BrickBox& occupancy_box,
                                   vk::BufferView map_view, const Cast& cast, int bands) {
  const gpu::RaycastParams& p = setup.params;
  const gpu::GpuImage3D* map = request.backward_map ? request.backward_map : &*identity_map_;
  const bool sampled = options_.volume_access == VolumeAccess::kSampler3D;
  const bool has_map = request.backward_map != nullptr;
  const bool occupancy = request.settings.empty_space_skipping && !occupancy_box.empty();
  if (request.settings.count_samples) RETURN_IF_ERROR(batch.Fill(*stats_, 0));
  // The map's texel copy serves the occupancy pass and the texel-buffer ray
  // casters.
  const bool in_place = has_map && request.backward_map_texels != nullptr;
  if (has_map && !in_place && (occupancy || !sampled)) {
    RETURN_IF_ERROR(batch.CopyImageToBuffer(*map, *map_texels_, "map_copy"));
  }
  if (occupancy) {
    const glm::ivec3& box = occupancy_box.size;
    const int bricks = int(occupancy_box.count());
    const gpu::BrickOccupancyPush push{
        .dims = glm::ivec4(glm::ivec3(p.dims), 0),
        .bricks = p.bricks,
        .brick_voxels = p.brick_voxels,
        .spacing_mm = p.spacing_mm,
        .lut = p.lut,
        .flags = glm::ivec4(p.dims.w, has_map ? 1 : 0, box.x, box.y),
        .map_dims = glm::vec4(glm::vec3(map->extent()[0], map->extent()[1], map->extent()[2]),
                              0.0f),
        .box_lo = glm::ivec4(occupancy_box.lo, box.z)};
    RETURN_IF_ERROR(batch.Dispatch(*occupancy_kernel_,
                                   {&minmax, map_view, &*nonzero_prefix_, &*occupancy_},
                                   push, {GroupCount(bricks, 64), 1, 1}, "occupancy"));
  }
  RETURN_IF_ERROR(RecordBand(batch, cast, setup, 0, bands));
  if (upscale) {
    const gpu::UpscalePush push{
        .size = glm::ivec4(setup.render_width, setup.render_height, request.width,
                           request.height),
        .mode = glm::ivec4(UpscaleFilterOf(request), 0, 0, 0)};
    RETURN_IF_ERROR(batch.Dispatch(*upscale_kernel_, {&*pixels_, &*upscaled_}, push,
                                   {GroupCount(request.width, 8 * kUpscalePixelsPerInvocation),
                                    GroupCount(request.height, 8), 1},
                                   "upscale"));
  }
  return absl::OkStatus();
}

Result<VolumeRenderer::Cast> VolumeRenderer::PrepareCast(const RenderRequest& request,
                                                         const RaycastSetup& setup,
                                                         vk::BufferView map_view) {
  const bool sampled = options_.volume_access == VolumeAccess::kSampler3D;
  const bool mip = request.mode == RenderMode::kMip;
  const bool has_map = request.backward_map != nullptr;
  const gpu::GpuImage3D* map = has_map ? request.backward_map : &*identity_map_;
  const gpu::KernelArg volume_arg = sampled ? gpu::KernelArg(request.volume_image)
                                            : gpu::KernelArg(request.volume->texel_view());
  const gpu::KernelArg map_arg = sampled ? gpu::KernelArg(map) : gpu::KernelArg(map_view);
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   request.volume->KernelFor(
                       *context_, (setup.params.image.z & kRaycastPreintegrated) != 0
                                      ? *preintegrated_kernels_[has_map]
                                  : (setup.params.image.z & kRaycastCellGradient) != 0
                                      ? *cell_gradient_kernels_[has_map]
                                      : *raycast_kernels_[mip][has_map]));
  return Cast{std::move(kernel),
              {volume_arg, map_arg, &*params_, *lut_view_, *occupancy_view_, &*pixels_, &*stats_}};
}

Status VolumeRenderer::RecordBand(gpu::ComputeBatch& batch, const Cast& cast,
                                  const RaycastSetup& setup, int band, int bands) {
  const gpu::RaycastBandPush push{.rows =
                                      glm::ivec4(band, bands, int(options_.dispatch_threads), 0)};
  // Tile rows band, band + bands, ... below the frame's GroupCount(height).
  const uint32_t tile_rows = GroupCount(setup.render_height, 8);
  const uint32_t rows = (tile_rows - uint32_t(band) + uint32_t(bands) - 1) / uint32_t(bands);
  return batch.Dispatch(cast.kernel, cast.args,
                        std::as_bytes(std::span<const gpu::RaycastBandPush>(&push, 1)),
                        {GroupCount(setup.render_width, 8), rows, 1}, "raycast");
}

int VolumeRenderer::Bands(const RenderRequest& request, int width, int height) const {
  if (request.quality != RenderQuality::kStill || options_.still_band_rays <= 0) return 1;
  const int64_t rays = int64_t(width) * height;
  const int64_t tile_rows = (height + 7) / 8;
  int64_t bands = rays / options_.still_band_rays;
  if (options_.still_band_ms > 0.0 && still_ms_per_ray_ >= 0.0) {
    // The last still's cost per ray (ms) at this one's rays.
    const double still_ms = still_ms_per_ray_ * double(rays);
    // Whole where that is under half of still_band_ms: on a fast device a
    // band's dispatch is too small to fill it (docs/RENDERING.md, "Stills
    // in bands").
    if (2.0 * still_ms <= options_.still_band_ms) return 1;
    // More bands where still_band_rays would take longer than
    // still_band_ms: a band bounds what waits behind it.
    bands = std::max(
        bands, int64_t(std::ceil(std::min(still_ms / options_.still_band_ms, double(tile_rows)))));
  }
  return int(std::clamp<int64_t>(bands, 1, tile_rows));
}

Result<vk::raii::BufferView> VolumeRenderer::CallerMapView(const RenderRequest& request,
                                                           size_t points) const {
  const gpu::GpuBuffer* texels = request.backward_map_texels;
  if (points > context_->limits().maxTexelBufferElements ||
      texels->size_bytes() < points * sizeof(glm::vec4)) {
    return absl::InvalidArgumentError(
        StrCat("backward_map_texels: ", texels->size_bytes(), " bytes for a map of ", points,
               " points (16 bytes each, at most ", context_->limits().maxTexelBufferElements,
               " texels)"));
  }
  vk::raii::BufferView view{nullptr};
  RETURN_IF_ERROR(gpu::CatchVulkan("creating a view of the backward map's values", [&] {
    view = vk::raii::BufferView(
        context_->device(), vk::BufferViewCreateInfo({}, texels->handle(),
                                                     vk::Format::eR32G32B32A32Sfloat, 0,
                                                     points * sizeof(glm::vec4)));
  }));
  return view;
}

VolumeRenderer::OccupancyPlan VolumeRenderer::PlanOccupancy(
    const RenderRequest& request, const gpu::RaycastParams& p,
    const std::array<int, 3>& map_dims) const {
  OccupancyPlan plan{
      .key = {request.volume, request.volume->buffer().handle(), request.mode, lut_generation_,
              glm::ivec3(p.brick_voxels), request.backward_map, request.backward_map_version},
      .cacheable = request.backward_map == nullptr || request.backward_map_version != 0,
      .box = {glm::ivec3(0), glm::ivec3(p.bricks)}};
  plan.current = plan.cacheable && occupancy_key_ == plan.key;
  if (plan.current) {
    plan.box = {};
  } else if (plan.cacheable && request.backward_map != nullptr && occupancy_key_ &&
             request.backward_map_previous_version != 0) {
    // The occupancy of the map's previous version: only the bricks whose
    // map cells the update changed.
    OccupancyKey previous = plan.key;
    previous.map_version = request.backward_map_previous_version;
    if (*occupancy_key_ == previous) {
      plan.box = BricksMeetingMapBox(p, map_dims, request.backward_map_changed_lo,
                                     request.backward_map_changed_hi);
    }
  }
  return plan;
}

Status VolumeRenderer::ReadBack(const RenderRequest& request, const RaycastSetup& setup,
                                bool upscale, std::span<const gpu::DispatchTiming> timings,
                                Frame& frame) {
  for (const auto& t : timings) {
    if (t.label == "occupancy") frame.timings.occupancy_ms = t.gpu_ms;
    if (t.label == "map_copy") frame.timings.map_copy_ms = t.gpu_ms;
    if (t.label == "raycast") {
      // Summed over the bands; -1 when the device has no timestamps.
      const double so_far = frame.timings.raycast_ms;
      frame.timings.raycast_ms = t.gpu_ms < 0 || so_far < 0 ? -1.0 : so_far + t.gpu_ms;
    }
    if (t.label == "upscale") frame.timings.upscale_ms = t.gpu_ms;
    frame.timings.render_ms += std::max(0.0, t.gpu_ms);
  }
  const auto t0 = std::chrono::steady_clock::now();
  frame.rgba.resize(size_t(request.width) * request.height * 4);
  RETURN_IF_ERROR((upscale ? *upscaled_ : *pixels_).Download(std::as_writable_bytes(
      std::span<uint8_t>(frame.rgba))));
  frame.timings.readback_ms = MsSince(t0);
  if (!request.settings.count_samples) return absl::OkStatus();
  uint32_t samples = 0;
  RETURN_IF_ERROR(stats_->Download(std::as_writable_bytes(std::span<uint32_t>(&samples, 1))));
  frame.samples = samples;
  if (request.settings.empty_space_skipping) {
    std::vector<float> occupancy(size_t(frame.total_bricks));
    RETURN_IF_ERROR(occupancy_->DownloadSpan(std::span<float>(occupancy)));
    const bool mip = request.mode == RenderMode::kMip;
    const float black = setup.params.window.x;
    frame.occupied_bricks = std::count_if(occupancy.begin(), occupancy.end(), [&](float o) {
      return mip ? o > black : o > 0.0f;
    });
  }
  return absl::OkStatus();
}

Result<vk::raii::BufferView> VolumeRenderer::PrepareMapTexels(
    const RenderRequest& request, const std::array<int, 3>& map_dims) {
  vk::raii::BufferView map_view{nullptr};
  if (!request.backward_map) return map_view;
  const size_t points = size_t(map_dims[0]) * map_dims[1] * map_dims[2];
  if (request.backward_map_texels) return CallerMapView(request, points);
  RETURN_IF_ERROR(EnsureMapTexels(points));
  return map_view;
}

void VolumeRenderer::RememberStillCost(std::span<const gpu::DispatchTiming> timings,
                                       double submits_ms, size_t rays) {
  double cast_ms = 0.0;
  for (const auto& t : timings) {
    if (t.label != "raycast") continue;
    if (t.gpu_ms < 0.0) {  // no timestamps: the wall time of the submits
      cast_ms = submits_ms;
      break;
    }
    cast_ms += t.gpu_ms;
  }
  if (rays > 0) still_ms_per_ray_ = cast_ms / double(rays);
}

double VolumeRenderer::PredictStillMs(int64_t rays) const {
  const double per_ray = still_ms_per_ray_.load();
  return per_ray < 0.0 ? -1.0 : per_ray * double(rays);
}

int VolumeRenderer::BandsPerSubmit(double band0_ms, int bands) const {
  if (options_.still_band_ms <= 0.0 || bands <= 2 || band0_ms < 0.0) return 1;
  // band0_ms 0 (under the timestamps' resolution): all in one submit.
  const double fit = band0_ms > 0.0 ? std::floor(options_.still_band_ms / band0_ms) : bands;
  return int(std::clamp(fit, 1.0, double(bands - 1)));
}

Result<int> VolumeRenderer::SubmitOtherBands(const RenderRequest& request, const Cast& cast,
                                             const RaycastSetup& setup, int bands, double band0_ms,
                                             std::vector<gpu::DispatchTiming>& timings) {
  // What another renderer submits meanwhile runs between two submits.
  const int per_submit = BandsPerSubmit(band0_ms, bands);
  int submits = 0;
  for (int b = 1; b < bands; b += per_submit) {
    RETURN_IF_ERROR(request.cancel.Check());
    const int end = std::min(bands, b + per_submit);
    ASSIGN_OR_RETURN(auto batch, gpu::ComputeBatch::Begin(*context_, uint32_t(end - b)));
    for (int band = b; band < end; ++band) {
      RETURN_IF_ERROR(RecordBand(batch, cast, setup, band, bands));
    }
    ASSIGN_OR_RETURN(auto band_timings, batch.SubmitAndWait());
    timings.insert(timings.end(), band_timings.begin(), band_timings.end());
    ++submits;
  }
  return submits;
}

Result<std::vector<gpu::DispatchTiming>> VolumeRenderer::SubmitFrame(
    gpu::ComputeBatch& batch, const RenderRequest& request, const RaycastSetup& setup,
    const Cast& cast, const OccupancyPlan& occupancy, int bands, int& submits) {
  const auto t_submit = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(auto timings, batch.SubmitAndWait());
  if (request.settings.empty_space_skipping && occupancy.cacheable) {
    occupancy_key_ = occupancy.key;
  }
  ASSIGN_OR_RETURN(
      const int other_submits,
      SubmitOtherBands(request, cast, setup, bands, Band0Ms(timings, MsSince(t_submit)), timings));
  submits = 1 + other_submits;
  if (request.quality == RenderQuality::kStill) {
    RememberStillCost(timings, MsSince(t_submit), size_t(setup.render_width) * setup.render_height);
  }
  return timings;
}

Result<Frame> VolumeRenderer::Render(const RenderRequest& request) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto t_start = std::chrono::steady_clock::now();
  RETURN_IF_ERROR(CheckGpuInputs(request));
  std::array<int, 3> map_dims{0, 0, 0};
  if (request.backward_map) {
    const auto& e = request.backward_map->extent();
    map_dims = {int(e[0]), int(e[1]), int(e[2])};
  }
  ASSIGN_OR_RETURN(RaycastSetup setup,
                   PrepareRaycast(request, request.volume->geometry(), map_dims));
  RETURN_IF_ERROR(PrepareLut(request.preset, setup.step_mm,
                             (setup.params.image.z & kRaycastPreintegrated) != 0));
  setup.params.lut = lut_params_;
  ASSIGN_OR_RETURN(const gpu::GpuBuffer* minmax,
                   BrickMinMax(*request.volume, glm::ivec3(setup.params.brick_voxels)));

  const gpu::RaycastParams& p = setup.params;
  const size_t bricks = size_t(p.bricks.x) * p.bricks.y * p.bricks.z;
  const size_t render_pixels = size_t(setup.render_width) * setup.render_height;
  const size_t out_pixels = size_t(request.width) * request.height;
  const bool upscale = render_pixels != out_pixels;
  RETURN_IF_ERROR(EnsureOccupancy(bricks));
  RETURN_IF_ERROR(EnsureBuffer(pixels_, render_pixels * 4, BU::eStorageBuffer));
  ASSIGN_OR_RETURN(vk::raii::BufferView map_view, PrepareMapTexels(request, map_dims));
  const OccupancyPlan occupancy = PlanOccupancy(request, p, map_dims);
  occupancy_key_.reset();  // until this frame's pass has run
  if (upscale) RETURN_IF_ERROR(EnsureBuffer(upscaled_, out_pixels * 4, BU::eStorageBuffer));
  RETURN_IF_ERROR(params_->Upload(std::as_bytes(std::span<const gpu::RaycastParams>(&p, 1))));

  // The texels the kernels read for the map: the caller's buffer in place,
  // else the renderer's copy of the image.
  const vk::BufferView map_texels =
      request.backward_map && request.backward_map_texels ? *map_view : *map_texels_view_;
  const int bands = Bands(request, setup.render_width, setup.render_height);
  ASSIGN_OR_RETURN(const Cast cast, PrepareCast(request, setup, map_texels));
  ASSIGN_OR_RETURN(auto batch, gpu::ComputeBatch::Begin(*context_, 5));
  RETURN_IF_ERROR(RecordFrame(batch, request, setup, *minmax, upscale, occupancy.box, map_texels,
                              cast, bands));
  int submits = 0;
  ASSIGN_OR_RETURN(auto timings,
                   SubmitFrame(batch, request, setup, cast, occupancy, bands, submits));
  const bool skipping = request.settings.empty_space_skipping;
  Frame frame{.width = request.width,
              .height = request.height,
              .render_width = setup.render_width,
              .render_height = setup.render_height,
              .step_mm = setup.step_mm,
              .bands = bands,
              .submits = submits,
              .total_bricks = int64_t(bricks),
              .occupancy_reused = skipping && occupancy.current,
              .occupancy_bricks_computed = skipping ? occupancy.box.count() : 0};
  RETURN_IF_ERROR(ReadBack(request, setup, upscale, timings, frame));
  const auto t0 = std::chrono::steady_clock::now();
  DrawOverlay(request.overlay, request.camera, frame.width, frame.height, frame.rgba);
  frame.timings.overlay_ms = MsSince(t0);
  frame.timings.wall_ms = MsSince(t_start);
  return frame;
}

}  // namespace vpm

#include "server/render/backward_map.h"

#include <algorithm>
#include <numeric>

#include "server/gpu/compute_batch.h"
#include "server/render/check_map_inputs.h"
#include "shaders/backward_map.spv.h"

namespace vpm {
namespace {

using gpu::BackwardMapTetWork;

constexpr int kPassReset = 0;
constexpr int kPassClear = 1;
constexpr int kPassClaim = 2;
constexpr int kPassWrite = 3;
constexpr uint32_t kLocalSize = 64;

Status EnsureCapacity(const gpu::GpuContext& context, std::optional<gpu::GpuBuffer>& buffer,
                      size_t bytes) {
  bytes = std::max<size_t>(bytes, 16);
  if (buffer && buffer->size_bytes() >= bytes) return absl::OkStatus();
  ASSIGN_OR_RETURN(gpu::GpuBuffer grown,
                   gpu::GpuBuffer::Create(context, bytes, vk::BufferUsageFlagBits::eStorageBuffer));
  buffer.emplace(std::move(grown));
  return absl::OkStatus();
}

glm::ivec4 WithW(const glm::ivec3& v, int w) { return glm::ivec4(v, w); }

}  // namespace

Result<BackwardMap> BackwardMap::Create(const gpu::GpuContext& context,
                                        const VolumeGeometry& geometry, const Options& options) {
  std::array<int64_t, 3> dims = options.map_dims;
  if (dims == std::array<int64_t, 3>{0, 0, 0}) dims = DefaultBackwardMapDims(geometry.dims);
  RETURN_IF_ERROR(CheckMapGrid(geometry.extent_mm(), dims,
                               context.limits().maxImageDimension3D));
  if (!(options.eps >= 0.0 && options.eps < 1.0)) {
    return absl::InvalidArgumentError(StrCat("backward map: eps ", options.eps,
                                             " must be in [0, 1)"));
  }
  constexpr vk::Format kFormat = vk::Format::eR32G32B32A32Sfloat;
  const auto features = context.physical_device().getFormatProperties(kFormat).optimalTilingFeatures;
  const auto needed = vk::FormatFeatureFlagBits::eStorageImage |
                      vk::FormatFeatureFlagBits::eSampledImageFilterLinear;
  if ((features & needed) != needed) {
    return absl::FailedPreconditionError(
        "backward map: this device cannot store to or linearly filter RGBA32F 3D images");
  }
  const uint64_t points = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
  if (points * sizeof(uint32_t) > context.limits().maxStorageBufferRange) {
    return absl::ResourceExhaustedError(StrCat(
        "backward map of ", dims[0], "x", dims[1], "x", dims[2], " points: its owner buffer of ",
        points * sizeof(uint32_t), " bytes exceeds the device's storage-buffer range of ",
        context.limits().maxStorageBufferRange));
  }
  ASSIGN_OR_RETURN(gpu::ComputeKernel kernel,
                   gpu::ComputeKernel::Create(
                       context, {.name = "backward_map",
                                 .spirv = kBackwardMapSpv,
                                 .bindings = {vk::DescriptorType::eStorageBuffer,
                                              vk::DescriptorType::eStorageBuffer,
                                              vk::DescriptorType::eStorageBuffer,
                                              vk::DescriptorType::eStorageBuffer,
                                              vk::DescriptorType::eStorageBuffer,
                                              vk::DescriptorType::eStorageImage},
                                 .push_constant_bytes = sizeof(gpu::BackwardMapPush),
                                 .local_size = {kLocalSize, 1, 1}}));
  ASSIGN_OR_RETURN(gpu::GpuImage3D image,
                   gpu::GpuImage3D::Create(
                       context, {uint32_t(dims[0]), uint32_t(dims[1]), uint32_t(dims[2])}, kFormat));
  ASSIGN_OR_RETURN(gpu::GpuBuffer owner,
                   gpu::GpuBuffer::Create(context, points * sizeof(uint32_t),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  BackwardMap map(context, geometry, dims, options.eps, std::move(kernel), std::move(image),
                  std::move(owner));
  RETURN_IF_ERROR(EnsureCapacity(context, map.tets_buffer_, 0));
  RETURN_IF_ERROR(EnsureCapacity(context, map.deformed_buffer_, 0));
  RETURN_IF_ERROR(EnsureCapacity(context, map.rest_offset_buffer_, 0));
  RETURN_IF_ERROR(EnsureCapacity(context, map.work_buffer_, 0));
  RETURN_IF_ERROR(map.Run(/*full=*/true, 0).status());
  return map;
}

Result<BackwardMap::UpdateStats> BackwardMap::Update(
    std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
    std::span<const std::array<int32_t, 4>> tets) {
  return Apply(rest_mm, deformed_mm, tets, Scope::kChanged, {});
}

Result<BackwardMap::UpdateStats> BackwardMap::UpdateListed(
    std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
    std::span<const std::array<int32_t, 4>> tets, std::span<const int32_t> moved_tets) {
  return Apply(rest_mm, deformed_mm, tets, Scope::kListed, moved_tets);
}

Result<BackwardMap::UpdateStats> BackwardMap::Rebuild(
    std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
    std::span<const std::array<int32_t, 4>> tets) {
  return Apply(rest_mm, deformed_mm, tets, Scope::kAll, {});
}

std::vector<int32_t> BackwardMap::ChangedTets(std::span<const glm::dvec3> rest_mm,
                                              std::span<const glm::dvec3> deformed_mm,
                                              std::span<const std::array<int32_t, 4>> tets) const {
  std::vector<uint8_t> changed(rest_mm.size(), 0);
  for (size_t v = 0; v < rest_mm.size(); ++v) {
    changed[v] = rest_mm[v] != state_.rest_mm[v] || deformed_mm[v] != state_.deformed_mm[v];
  }
  std::vector<int32_t> moved;
  for (size_t t = 0; t < tets.size(); ++t) {
    const auto& q = tets[t];
    if (changed[q[0]] || changed[q[1]] || changed[q[2]] || changed[q[3]]) {
      moved.push_back(static_cast<int32_t>(t));
    }
  }
  return moved;
}

Result<BackwardMap::UpdateStats> BackwardMap::Apply(std::span<const glm::dvec3> rest_mm,
                                                    std::span<const glm::dvec3> deformed_mm,
                                                    std::span<const std::array<int32_t, 4>> tets,
                                                    Scope scope,
                                                    std::span<const int32_t> moved_tets) {
  RETURN_IF_ERROR(CheckMapMesh(rest_mm, deformed_mm, tets));
  const int64_t tet_count = static_cast<int64_t>(tets.size());
  for (int32_t t : moved_tets) {
    if (t < 0 || t >= tet_count) {
      return absl::InvalidArgumentError(StrCat("backward map: moved tet ", t, " outside [0, ",
                                               tet_count, ")"));
    }
  }
  UpdateStats stats;
  stats.full_rebuild = scope == Scope::kAll || !state_.valid ||
                       rest_mm.size() != state_.rest_mm.size() ||
                       !std::equal(tets.begin(), tets.end(), state_.tets.begin(),
                                   state_.tets.end());
  std::vector<int32_t> moved;
  if (stats.full_rebuild) {
    moved.resize(tets.size());
    std::iota(moved.begin(), moved.end(), 0);
  } else if (scope == Scope::kListed) {
    moved.assign(moved_tets.begin(), moved_tets.end());
    std::sort(moved.begin(), moved.end());
    moved.erase(std::unique(moved.begin(), moved.end()), moved.end());
  } else {
    moved = ChangedTets(rest_mm, deformed_mm, tets);
  }
  stats.moved_tets = static_cast<int64_t>(moved.size());

  const glm::dvec3 step = extent_mm() / glm::dvec3(dims_[0] - 1, dims_[1] - 1, dims_[2] - 1);
  std::vector<GridBox> boxes = stats.full_rebuild ? std::vector<GridBox>(tets.size())
                                                  : state_.boxes;
  for (int32_t t : moved) {
    const auto& q = tets[t];
    boxes[t] = TetGridBox({deformed_mm[q[0]], deformed_mm[q[1]], deformed_mm[q[2]],
                           deformed_mm[q[3]]},
                          step, dims_, eps_);
  }
  std::vector<int32_t> listed = moved;
  if (!stats.full_rebuild) {
    // Every point a moved tet covered or covers is redone by every tet that
    // may contain it, so the owners come out as in a full rebuild.
    std::vector<GridBox> region;
    for (int32_t t : moved) {
      region.push_back(state_.boxes[t]);
      region.push_back(boxes[t]);
    }
    std::vector<int32_t> meeting = TetsMeetingBoxes(boxes, region, dims_);
    std::vector<int32_t> merged;
    std::set_union(moved.begin(), moved.end(), meeting.begin(), meeting.end(),
                   std::back_inserter(merged));
    listed = std::move(merged);
  }
  stats.processed_tets = static_cast<int64_t>(listed.size());
  std::vector<BackwardMapTetWork> work;
  work.reserve(listed.size());
  for (int32_t t : listed) {
    const GridBox old_box = stats.full_rebuild ? GridBox{} : state_.boxes[t];
    work.push_back({WithW(old_box.lo, t), WithW(old_box.hi, 0), WithW(boxes[t].lo, 0),
                    WithW(boxes[t].hi, 0)});
  }

  state_.valid = false;  // until the GPU holds what the host state says
  if (stats.full_rebuild || !work.empty()) {
    RETURN_IF_ERROR(Upload(rest_mm, deformed_mm, tets, stats.full_rebuild, work));
    ASSIGN_OR_RETURN(stats.gpu_ms, Run(stats.full_rebuild, static_cast<uint32_t>(work.size())));
  }
  state_.rest_mm.assign(rest_mm.begin(), rest_mm.end());
  state_.deformed_mm.assign(deformed_mm.begin(), deformed_mm.end());
  if (stats.full_rebuild) state_.tets.assign(tets.begin(), tets.end());
  state_.boxes = std::move(boxes);
  state_.valid = true;
  return stats;
}

Status BackwardMap::Upload(std::span<const glm::dvec3> rest_mm,
                           std::span<const glm::dvec3> deformed_mm,
                           std::span<const std::array<int32_t, 4>> tets, bool upload_tets,
                           std::span<const BackwardMapTetWork> work) {
  const size_t n = rest_mm.size();
  std::vector<glm::vec4> deformed(n), rest_offset(n);
  for (size_t v = 0; v < n; ++v) {
    deformed[v] = glm::vec4(glm::vec3(deformed_mm[v]), 0.0f);
    // Rest minus deformed in double, then rounded: the map value is a blend
    // of these, accurate to float relative to the displacement, not to the
    // coordinates.
    rest_offset[v] = glm::vec4(glm::vec3(rest_mm[v] - deformed_mm[v]), 0.0f);
  }
  RETURN_IF_ERROR(EnsureCapacity(*context_, deformed_buffer_, n * sizeof(glm::vec4)));
  RETURN_IF_ERROR(EnsureCapacity(*context_, rest_offset_buffer_, n * sizeof(glm::vec4)));
  RETURN_IF_ERROR(EnsureCapacity(*context_, work_buffer_, work.size() * sizeof(work[0])));
  RETURN_IF_ERROR(deformed_buffer_->UploadSpan(std::span<const glm::vec4>(deformed)));
  RETURN_IF_ERROR(rest_offset_buffer_->UploadSpan(std::span<const glm::vec4>(rest_offset)));
  RETURN_IF_ERROR(work_buffer_->UploadSpan(work));
  if (upload_tets) {
    RETURN_IF_ERROR(EnsureCapacity(*context_, tets_buffer_, tets.size() * sizeof(glm::uvec4)));
    RETURN_IF_ERROR(tets_buffer_->UploadSpan(tets));
  }
  return absl::OkStatus();
}

Result<double> BackwardMap::Run(bool full, uint32_t listed) {
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 3));
  gpu::BackwardMapPush push{
      .map_dims = glm::ivec4(dims_[0], dims_[1], dims_[2], kPassReset),
      .step_mm = glm::vec4(glm::vec3(extent_mm() / glm::dvec3(dims_[0] - 1, dims_[1] - 1,
                                                              dims_[2] - 1)),
                           float(eps_)),
      .work = glm::uvec4(listed, 0, 0, 0)};
  auto dispatch = [&](int pass, std::array<uint32_t, 3> groups, const char* label) {
    push.map_dims.w = pass;
    return batch.Dispatch(kernel_,
                          {&*tets_buffer_, &*deformed_buffer_, &*rest_offset_buffer_,
                           &*work_buffer_, &owner_, &image_},
                          push, groups, label);
  };
  if (full) {
    RETURN_IF_ERROR(dispatch(kPassReset,
                             {uint32_t((dims_[0] + kLocalSize - 1) / kLocalSize),
                              uint32_t(dims_[1]), uint32_t(dims_[2])},
                             "backward_map reset"));
  }
  if (listed > 0) {
    // One workgroup per listed tet, folded into 2D past the x limit.
    const uint32_t gx = std::min(listed, context_->limits().maxComputeWorkGroupCount[0]);
    const std::array<uint32_t, 3> groups{gx, (listed + gx - 1) / gx, 1};
    if (!full) RETURN_IF_ERROR(dispatch(kPassClear, groups, "backward_map clear"));
    RETURN_IF_ERROR(dispatch(kPassClaim, groups, "backward_map claim"));
    RETURN_IF_ERROR(dispatch(kPassWrite, groups, "backward_map write"));
  }
  ASSIGN_OR_RETURN(const auto timings, batch.SubmitAndWait());
  double ms = 0.0;
  for (const auto& t : timings) {
    if (t.gpu_ms < 0) return -1.0;
    ms += t.gpu_ms;
  }
  return ms;
}

Result<BackwardMapValues> BackwardMap::Download() const {
  BackwardMapValues map;
  map.dims = dims_;
  map.extent_mm = extent_mm();
  map.values.resize(static_cast<size_t>(dims_[0] * dims_[1] * dims_[2]));
  RETURN_IF_ERROR(image_.Download(std::as_writable_bytes(std::span<glm::vec4>(map.values))));
  return map;
}

}  // namespace vpm

#include "server/warp/backward_map.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <string>
#include <string_view>
#include <utility>

#include "server/common/clock.h"
#include "server/warp/check_map_inputs.h"
#include "server/warp/tet_displacement_frame.h"
#include "shaders/backward_map.spv.h"
#include "shaders/backward_map_write.spv.h"

namespace vpm {
namespace {

using gpu::BackwardMapTetWork;

constexpr int kPassClear = 0;
constexpr int kPassClaim = 1;
constexpr uint32_t kMapLocalSize = 16;       // backward_map.comp: lanes per tet
constexpr uint32_t kMapTetsPerGroup = 4;     // backward_map.comp: tets per workgroup
constexpr uint32_t kWriteLocalSize = 64;  // backward_map_write.comp: points per workgroup
constexpr uint32_t kNoOwner = 0xFFFFFFFFu;
constexpr vk::Format kMapFormat = vk::Format::eR32G32B32A32Sfloat;
constexpr int64_t kMaxValueSlabs = 4;  // values0..3 in backward_map.comp
constexpr std::string_view kCopyLabel = "backward_map copy";

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

GridBox Union(const GridBox& a, const GridBox& b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)};
}

// Tet t's work items, its old box (cleared) and new box (claimed), one per
// slab of z-slices small enough that no lane of the claim and clear passes
// loops more than kLaneIterations times: llvmpipe ends every loop of an
// invocation silently once their iterations add up to 65,535
// (LP_MAX_TGSI_LOOP_ITERATIONS, Mesa 22.3), which left large tets on fine
// grids half claimed (docs/WARP.md). Returns the items appended.
uint32_t AppendSlabs(int32_t t, const GridBox& old_box, const GridBox& new_box,
                     std::vector<gpu::BackwardMapTetWork>& work) {
  const GridBox both = Union(old_box, new_box);
  if (both.empty()) return 0;
  const glm::ivec3 size = both.hi - both.lo + 1;
  constexpr int64_t kLaneIterations = 30000;  // of the 65,535
  // A slice's rows shared by the kMapLocalSize lanes, each row its points plus
  // row_range's few loop steps.
  const int64_t per_slice =
      (int64_t(size.y) + kMapLocalSize - 1) / kMapLocalSize * (int64_t(size.x) + 8);
  const int slab = static_cast<int>(std::max<int64_t>(1, kLaneIterations / per_slice));
  uint32_t added = 0;
  for (int z0 = both.lo.z; z0 <= both.hi.z; z0 += slab) {
    const int z1 = std::min(z0 + slab - 1, both.hi.z);
    auto cut = [&](const GridBox& b) {
      GridBox c = b;
      c.lo.z = std::max(b.lo.z, z0);
      c.hi.z = std::min(b.hi.z, z1);
      return c;
    };
    const GridBox o = cut(old_box), w = cut(new_box);
    work.push_back({WithW(o.lo, t), WithW(o.hi, 0), WithW(w.lo, 0), WithW(w.hi, 0)});
    ++added;
  }
  return added;
}

// The points per values slab (whole z slices, within one storage binding),
// after checking what the device must offer for a map of `dims` points.
Result<uint32_t> SlabPoints(const gpu::GpuContext& context, const std::array<int64_t, 3>& dims,
                            int64_t max_slab_bytes) {
  const vk::FormatProperties props = context.physical_device().getFormatProperties(kMapFormat);
  if (!(props.optimalTilingFeatures & vk::FormatFeatureFlagBits::eSampledImageFilterLinear)) {
    return absl::FailedPreconditionError(
        "backward map: this device cannot filter RGBA32F 3D images linearly");
  }
  const int64_t range = context.limits().maxStorageBufferRange;
  const int64_t slab_bytes = max_slab_bytes > 0 ? std::min(max_slab_bytes, range) : range;
  const int64_t slice = dims[0] * dims[1];
  const int64_t slices_per_slab = std::min<int64_t>(slab_bytes / (slice * 16), dims[2]);
  const int64_t points = slice * dims[2];
  if (points * 4 > range || slices_per_slab == 0 ||
      (dims[2] + slices_per_slab - 1) / slices_per_slab > kMaxValueSlabs) {
    return absl::ResourceExhaustedError(StrCat(
        "backward map of ", dims[0], "x", dims[1], "x", dims[2], " points: needs ", points * 4,
        " bytes of owners and ", points * 16, " of values; this device binds at most ", range,
        " bytes per storage buffer (owners in one, values in up to ", kMaxValueSlabs,
        " of whole z slices, ", slab_bytes, " bytes each)"));
  }
  return static_cast<uint32_t>(slices_per_slab * slice);
}

}  // namespace

Result<BackwardMap> BackwardMap::Create(const gpu::GpuContext& context,
                                        const VolumeGeometry& geometry, const Options& options) {
  std::array<int64_t, 3> dims = options.map_dims;
  if (dims == std::array<int64_t, 3>{0, 0, 0}) dims = DefaultBackwardMapDims(geometry.dims);
  RETURN_IF_ERROR(CheckMapGrid(geometry.extent_mm(), dims, context.limits().maxImageDimension3D));
  if (!(options.eps >= 0.0 && options.eps < 1.0)) {
    return absl::InvalidArgumentError(
        StrCat("backward map: eps ", options.eps, " must be in [0, 1)"));
  }
  ASSIGN_OR_RETURN(const uint32_t slab_points, SlabPoints(context, dims, options.max_slab_bytes));
  using DT = vk::DescriptorType;
  ASSIGN_OR_RETURN(
      gpu::ComputeKernel kernel,
      gpu::ComputeKernel::Create(
          context, {.name = "backward_map",
                    .spirv = kBackwardMapSpv,
                    .bindings = {DT::eStorageBuffer, DT::eStorageBuffer, DT::eStorageBuffer,
                                 DT::eStorageBuffer, DT::eStorageBuffer},
                    .push_constant_bytes = sizeof(gpu::BackwardMapPush),
                    .local_size = {kMapLocalSize * kMapTetsPerGroup, 1, 1}}));
  ASSIGN_OR_RETURN(
      gpu::ComputeKernel write_kernel,
      gpu::ComputeKernel::Create(
          context, {.name = "backward_map_write",
                    .spirv = kBackwardMapWriteSpv,
                    .bindings = {DT::eStorageBuffer, DT::eStorageBuffer, DT::eStorageBuffer,
                                 DT::eStorageBuffer, DT::eStorageBuffer, DT::eStorageBuffer},
                    .push_constant_bytes = sizeof(gpu::BackwardMapWritePush),
                    .local_size = {kWriteLocalSize, 1, 1}}));
  ASSIGN_OR_RETURN(
      gpu::GpuImage3D image,
      gpu::GpuImage3D::Create(context, {uint32_t(dims[0]), uint32_t(dims[1]), uint32_t(dims[2])},
                              kMapFormat));
  const uint64_t points = uint64_t(dims[0]) * uint64_t(dims[1]) * uint64_t(dims[2]);
  ASSIGN_OR_RETURN(gpu::GpuBuffer owner,
                   gpu::GpuBuffer::Create(context, points * sizeof(uint32_t),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  std::vector<gpu::GpuBuffer> values;
  for (uint64_t first = 0; first < points; first += slab_points) {
    ASSIGN_OR_RETURN(
        gpu::GpuBuffer slab,
        gpu::GpuBuffer::Create(context, std::min<uint64_t>(slab_points, points - first) * 16,
                               vk::BufferUsageFlagBits::eStorageBuffer |
                                   vk::BufferUsageFlagBits::eUniformTexelBuffer));
    values.push_back(std::move(slab));
  }
  BackwardMap map(context, geometry, dims, options,
                  Device{std::move(kernel), std::move(write_kernel), std::move(image),
                         std::move(owner), std::move(values), slab_points});
  for (auto* buffer : {&map.tets_buffer_, &map.deformed_buffer_, &map.previous_buffer_,
                       &map.frames_buffer_, &map.work_buffer_}) {
    RETURN_IF_ERROR(EnsureCapacity(context, *buffer, 0));
  }
  const GridBox all{glm::ivec3(0), glm::ivec3(dims[0] - 1, dims[1] - 1, dims[2] - 1)};
  RETURN_IF_ERROR(map.Run(/*full=*/true, 0, 0, all).status());
  return map;
}

Result<BackwardMap::UpdateStats> BackwardMap::Update(std::span<const glm::dvec3> rest_mm,
                                                     std::span<const glm::dvec3> deformed_mm,
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

BackwardMap::Plan BackwardMap::PlanWork(std::span<const glm::dvec3> deformed_mm,
                                        std::span<const std::array<int32_t, 4>> tets, bool full,
                                        const std::vector<int32_t>& moved) const {
  Plan plan;
  const glm::dvec3 step = extent_mm() / glm::dvec3(dims_[0] - 1, dims_[1] - 1, dims_[2] - 1);
  plan.boxes = full ? std::vector<GridBox>(tets.size()) : state_.boxes;
  for (int32_t t : moved) {
    const auto& q = tets[t];
    plan.boxes[t] =
        TetGridBox({deformed_mm[q[0]], deformed_mm[q[1]], deformed_mm[q[2]], deformed_mm[q[3]]},
                   step, dims_, eps_);
  }
  // Moved tets first (the clear pass takes those), then the unmoved tets
  // that may own a point a moved tet owned before.
  std::vector<int32_t> listed = moved;
  if (!full) {
    std::vector<GridBox> region;
    for (int32_t t : moved) region.push_back(state_.boxes[t]);
    for (int32_t t : TetsMeetingBoxes(plan.boxes, region)) {
      if (!std::binary_search(moved.begin(), moved.end(), t)) listed.push_back(t);
    }
  }
  plan.cleared = full ? 0 : static_cast<uint32_t>(moved.size());
  if (full) {
    plan.changed = {glm::ivec3(0), glm::ivec3(dims_[0] - 1, dims_[1] - 1, dims_[2] - 1)};
  }
  plan.listed_tets = static_cast<int64_t>(listed.size());
  uint32_t cleared_entries = 0;
  for (size_t n = 0; n < listed.size(); ++n) {
    const int32_t t = listed[n];
    const GridBox old_box = n < plan.cleared ? state_.boxes[t] : GridBox{};
    const GridBox& new_box = plan.boxes[t];
    // Only the moved tets' boxes, old and new, hold points whose value can
    // change: an unmoved listed tet claims only points it already held or
    // lost to a smaller index, except where a moved tet's clear freed them
    // (its old box). Their union is 40-60% of the one with the unmoved
    // tets' boxes on drag_loop_bench's steps.
    if (n < plan.cleared) plan.changed = Union(plan.changed, Union(old_box, new_box));
    const uint32_t added = AppendSlabs(t, old_box, new_box, plan.work);
    if (n < plan.cleared) cleared_entries += added;
  }
  plan.cleared = cleared_entries;
  return plan;
}

int64_t BackwardMap::HoldSmallMoves(std::span<const glm::dvec3> rest_mm,
                                    std::span<const glm::dvec3> deformed_mm,
                                    std::vector<glm::dvec3>& held_rest,
                                    std::vector<glm::dvec3>& held_deformed) const {
  held_rest.assign(rest_mm.begin(), rest_mm.end());
  held_deformed.assign(deformed_mm.begin(), deformed_mm.end());
  const auto within = [&](const glm::dvec3& a, const glm::dvec3& b) {
    const glm::dvec3 d = glm::abs(a - b);
    return std::max(d.x, std::max(d.y, d.z)) <= move_tolerance_mm_;
  };
  int64_t held = 0;
  for (size_t v = 0; v < held_rest.size(); ++v) {
    if ((rest_mm[v] != state_.rest_mm[v] || deformed_mm[v] != state_.deformed_mm[v]) &&
        within(rest_mm[v], state_.rest_mm[v]) && within(deformed_mm[v], state_.deformed_mm[v])) {
      held_rest[v] = state_.rest_mm[v];
      held_deformed[v] = state_.deformed_mm[v];
      ++held;
    }
  }
  return held;
}

std::vector<int32_t> BackwardMap::MovedTets(std::span<const glm::dvec3> rest_mm,
                                            std::span<const glm::dvec3> deformed_mm,
                                            std::span<const std::array<int32_t, 4>> tets,
                                            Scope scope, std::span<const int32_t> moved_tets,
                                            UpdateStats& stats) const {
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
  // With FEM nearly every tet moves on a drag step; then the clear pass
  // costs more than clearing everything (buffer fills) and rasterizing every
  // tet, which gives the same map (docs/WARP.md).
  if (!stats.full_rebuild && scope != Scope::kListed &&
      double(moved.size()) > full_rebuild_moved_fraction_ * double(tets.size())) {
    stats.full_rebuild = true;
    moved.resize(tets.size());
    std::iota(moved.begin(), moved.end(), 0);
  }
  return moved;
}

Status BackwardMap::RunPlan(std::span<const glm::dvec3> rest_mm,
                            std::span<const glm::dvec3> deformed_mm,
                            std::span<const std::array<int32_t, 4>> tets,
                            const std::vector<int32_t>& moved, const Plan& plan,
                            UpdateStats& stats) {
  RETURN_IF_ERROR(Upload(rest_mm, deformed_mm, tets, stats.full_rebuild, moved, plan.work));
  ASSIGN_OR_RETURN(std::vector<gpu::DispatchTiming> passes,
                   Run(stats.full_rebuild, uint32_t(plan.work.size()), plan.cleared, plan.changed));
  for (auto& pass : passes) {
    if (pass.label == kCopyLabel) {
      stats.copy_ms = std::max(pass.gpu_ms, 0.0);
      continue;
    }
    stats.gpu_ms = pass.gpu_ms < 0 || stats.gpu_ms < 0 ? -1.0 : stats.gpu_ms + pass.gpu_ms;
    stats.passes.push_back(std::move(pass));
  }
  std::swap(deformed_buffer_, previous_buffer_);
  return absl::OkStatus();
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
      return absl::InvalidArgumentError(
          StrCat("backward map: moved tet ", t, " outside [0, ", tet_count, ")"));
    }
  }
  UpdateStats stats;
  stats.full_rebuild =
      scope == Scope::kAll || !state_.valid || rest_mm.size() != state_.rest_mm.size() ||
      !std::equal(tets.begin(), tets.end(), state_.tets.begin(), state_.tets.end());
  // Update with a tolerance: vertices that moved less keep the positions of
  // the previous update, and the rest of this update sees those.
  std::vector<glm::dvec3> held_rest, held_deformed;
  if (!stats.full_rebuild && scope == Scope::kChanged && move_tolerance_mm_ > 0.0) {
    stats.held_vertices = HoldSmallMoves(rest_mm, deformed_mm, held_rest, held_deformed);
    rest_mm = held_rest;
    deformed_mm = held_deformed;
  }
  const std::vector<int32_t> moved =
      MovedTets(rest_mm, deformed_mm, tets, scope, moved_tets, stats);
  Plan plan = PlanWork(deformed_mm, tets, stats.full_rebuild, moved);
  stats.processed_tets = plan.listed_tets;
  if (stats.full_rebuild || !plan.work.empty()) stats.changed = plan.changed;

  state_.valid = false;  // until the GPU holds what the host state says
  if (stats.full_rebuild || !plan.work.empty()) {
    RETURN_IF_ERROR(RunPlan(rest_mm, deformed_mm, tets, moved, plan, stats));
  }
  state_.rest_mm.assign(rest_mm.begin(), rest_mm.end());
  state_.deformed_mm.assign(deformed_mm.begin(), deformed_mm.end());
  if (stats.full_rebuild) state_.tets.assign(tets.begin(), tets.end());
  state_.boxes = std::move(plan.boxes);
  state_.valid = true;
  return stats;
}

Status BackwardMap::Upload(std::span<const glm::dvec3> rest_mm,
                           std::span<const glm::dvec3> deformed_mm,
                           std::span<const std::array<int32_t, 4>> tets, bool full,
                           std::span<const int32_t> moved,
                           std::span<const BackwardMapTetWork> work) {
  const size_t n = rest_mm.size();
  std::vector<glm::vec4> deformed(n);
  for (size_t v = 0; v < n; ++v) deformed[v] = glm::vec4(glm::vec3(deformed_mm[v]), 0.0f);
  // The frames of unmoved tets are those of the previous update (same
  // corners). In double from the double positions, then rounded: the map
  // value is accurate to float relative to the displacement, not to the
  // coordinates.
  if (full) state_.frames.assign(tets.size() * 4, glm::vec4(0.0f));
  for (int32_t t : moved) {
    const auto& q = tets[t];
    const auto frame = TetDisplacementFrame(
        {rest_mm[q[0]], rest_mm[q[1]], rest_mm[q[2]], rest_mm[q[3]]},
        {deformed_mm[q[0]], deformed_mm[q[1]], deformed_mm[q[2]], deformed_mm[q[3]]});
    std::copy(frame.begin(), frame.end(), state_.frames.begin() + 4 * size_t(t));
  }
  RETURN_IF_ERROR(EnsureCapacity(*context_, deformed_buffer_, n * sizeof(glm::vec4)));
  RETURN_IF_ERROR(
      EnsureCapacity(*context_, frames_buffer_, state_.frames.size() * sizeof(glm::vec4)));
  RETURN_IF_ERROR(EnsureCapacity(*context_, work_buffer_, work.size() * sizeof(work[0])));
  RETURN_IF_ERROR(deformed_buffer_->UploadSpan(std::span<const glm::vec4>(deformed)));
  RETURN_IF_ERROR(frames_buffer_->UploadSpan(std::span<const glm::vec4>(state_.frames)));
  RETURN_IF_ERROR(work_buffer_->UploadSpan(work));
  if (full) {
    RETURN_IF_ERROR(EnsureCapacity(*context_, tets_buffer_, tets.size() * sizeof(glm::uvec4)));
    RETURN_IF_ERROR(tets_buffer_->UploadSpan(tets));
  }
  return absl::OkStatus();
}

Result<std::vector<gpu::DispatchTiming>> BackwardMap::Run(bool full, uint32_t listed,
                                                          uint32_t moved, const GridBox& changed) {
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch, gpu::ComputeBatch::Begin(*context_, 4));
  const glm::vec3 step_mm(extent_mm() / glm::dvec3(dims_[0] - 1, dims_[1] - 1, dims_[2] - 1));
  gpu::BackwardMapPush push{.map_dims = glm::ivec4(dims_[0], dims_[1], dims_[2], 0),
                            .step_mm = glm::vec4(step_mm, float(eps_)),
                            .work = glm::uvec4(listed, moved, 0, 0)};
  const uint32_t max_groups_x = context_->limits().maxComputeWorkGroupCount[0];
  auto dispatch = [&](int pass, uint32_t tets, const char* label) {
    push.map_dims.w = pass;
    // One workgroup per kMapTetsPerGroup tets, folded into 2D past the x
    // limit.
    const uint32_t groups = (tets + kMapTetsPerGroup - 1) / kMapTetsPerGroup;
    const uint32_t gx = std::min(groups, max_groups_x);
    return batch.Dispatch(kernel(),
                          {&*tets_buffer_, &*deformed_buffer_, &*work_buffer_, &device_.owner,
                           &*previous_buffer_},
                          push, {gx, (groups + gx - 1) / gx, 1}, label);
  };
  if (full) RETURN_IF_ERROR(batch.Fill(device_.owner, kNoOwner));
  if (moved > 0) RETURN_IF_ERROR(dispatch(kPassClear, moved, "backward_map clear"));
  if (listed > 0) RETURN_IF_ERROR(dispatch(kPassClaim, listed, "backward_map claim"));
  if (!changed.empty()) {
    // Every point of the box gets its owner's value (0 where none): points
    // whose owner did not change get the value they had, bit for bit.
    const glm::ivec3 size = changed.hi - changed.lo + 1;
    const uint32_t points = uint32_t(size.x) * uint32_t(size.y) * uint32_t(size.z);
    const uint32_t groups = (points + kWriteLocalSize - 1) / kWriteLocalSize;
    const uint32_t gx = std::min(groups, max_groups_x);
    const auto& v = device_.values;
    auto slab = [&](size_t s) { return &v[std::min(s, v.size() - 1)]; };
    const gpu::BackwardMapWritePush write_push{
        .map_dims = glm::ivec4(dims_[0], dims_[1], dims_[2], int32_t(device_.slab_points)),
        .step_mm = glm::vec4(step_mm, 0.0f),
        .box_lo = glm::ivec4(changed.lo, 0),
        .box_hi = glm::ivec4(changed.hi, 0)};
    RETURN_IF_ERROR(batch.Dispatch(device_.write_kernel,
                                   {&device_.owner, &*frames_buffer_, slab(0), slab(1), slab(2),
                                    slab(3)},
                                   write_push, {gx, (groups + gx - 1) / gx, 1},
                                   "backward_map write"));
  }
  RETURN_IF_ERROR(RecordCopyToImage(batch, changed));
  return batch.SubmitAndWait();
}

Status BackwardMap::RecordCopyToImage(gpu::ComputeBatch& batch, const GridBox& box) const {
  if (box.empty()) return absl::OkStatus();
  // One region per values slab the box meets.
  const int64_t slice = dims_[0] * dims_[1];
  const int64_t slab_slices = device_.slab_points / slice;
  std::vector<std::pair<const gpu::GpuBuffer*, vk::BufferImageCopy>> regions;
  for (size_t s = 0; s < device_.values.size(); ++s) {
    const int64_t z0 = std::max<int64_t>(box.lo.z, int64_t(s) * slab_slices);
    const int64_t z1 = std::min<int64_t>(box.hi.z, int64_t(s + 1) * slab_slices - 1);
    if (z0 > z1) continue;
    const int64_t first = box.lo.x + dims_[0] * box.lo.y + slice * (z0 - int64_t(s) * slab_slices);
    regions.emplace_back(
        &device_.values[s],
        vk::BufferImageCopy(
            vk::DeviceSize(first) * sizeof(glm::vec4), uint32_t(dims_[0]), uint32_t(dims_[1]),
            vk::ImageSubresourceLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1),
            vk::Offset3D(box.lo.x, box.lo.y, int32_t(z0)),
            vk::Extent3D(uint32_t(box.hi.x - box.lo.x + 1), uint32_t(box.hi.y - box.lo.y + 1),
                         uint32_t(z1 - z0 + 1))));
  }
  return batch.CopyBufferToImage(regions, device_.image, std::string(kCopyLabel));
}

Result<BackwardMapValues> BackwardMap::Download() const {
  BackwardMapValues map;
  map.dims = dims_;
  map.extent_mm = extent_mm();
  map.values.resize(static_cast<size_t>(dims_[0] * dims_[1] * dims_[2]));
  RETURN_IF_ERROR(device_.image.Download(std::as_writable_bytes(std::span<glm::vec4>(map.values))));
  return map;
}

}  // namespace vpm

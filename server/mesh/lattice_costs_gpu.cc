#include "server/mesh/lattice_costs_gpu.h"

#include <algorithm>

#include "server/gpu/compute_batch.h"
#include "server/gpu/shader_interface.h"
#include "server/volume/transfer_function_gpu.h"
#include "shaders/lattice_costs_cells.spv.h"
#include "shaders/lattice_costs_rows.spv.h"

namespace vpm {
namespace {

constexpr uint32_t kGroupSize = 64;      // local_size_x of both kernels
constexpr uint32_t kMaxGroupsX = 65535;  // the smallest maxComputeWorkGroupCount[0]

// Workgroups for `invocations` 1D invocations, folded into y past the limit.
std::array<uint32_t, 3> Groups(uint64_t invocations) {
  const uint64_t groups = (invocations + kGroupSize - 1) / kGroupSize;
  const uint64_t x = std::min<uint64_t>(groups, kMaxGroupsX);
  return {uint32_t(x), uint32_t((groups + x - 1) / x), 1};
}

// Cell layers [cz0, cz1) whose voxel slices are [z0, z1).
struct Chunk {
  int64_t cz0, cz1, z0, z1;
};

// Consecutive cell layers whose row partials fit in `budget` bytes (at least
// one layer per chunk).
std::vector<Chunk> ChunksOf(const Lattice& lattice, int64_t nx_cells, int64_t ny, size_t budget) {
  std::vector<Chunk> chunks;
  const int64_t gz = lattice.grid()[2];
  for (int64_t cz = 0; cz < gz;) {
    Chunk c{cz, cz, lattice.CellRange(2, cz)[0], lattice.CellRange(2, cz)[0]};
    while (c.cz1 < gz) {
      const int64_t z1 = lattice.CellRange(2, c.cz1)[1];
      const size_t bytes = size_t(nx_cells * ny * (z1 - c.z0)) * sizeof(glm::vec2);
      if (c.cz1 > c.cz0 && bytes > budget) break;
      c.z1 = z1;
      ++c.cz1;
    }
    chunks.push_back(c);
    cz = c.cz1;
  }
  return chunks;
}

}  // namespace

Result<LatticeCostsGpu> LatticeCostsGpu::Create(const gpu::GpuContext& context,
                                                size_t partials_budget_bytes) {
  LatticeCostsGpu op(context, partials_budget_bytes);
  // Build the default transfer function's kernels now, so that a shader
  // that does not build fails here rather than in the first mesh build.
  RETURN_IF_ERROR(op.KernelsFor(int(TransferFunction::CtSoftTissue().points().size())).status());
  return op;
}

Result<const LatticeCostsGpu::Kernels*> LatticeCostsGpu::KernelsFor(int tf_points) const {
  std::lock_guard lock(*mutex_);
  auto found = kernels_.find(tf_points);
  if (found != kernels_.end()) return found->second.get();
  using vk::DescriptorType;
  const std::vector<uint32_t> specialization{uint32_t(tf_points)};
  ASSIGN_OR_RETURN(
      gpu::ComputeKernel rows,
      gpu::ComputeKernel::Create(
          *context_, {.name = "lattice_costs_rows",
                      .spirv = kLatticeCostsRowsSpv,
                      .bindings = {DescriptorType::eUniformTexelBuffer,
                                   DescriptorType::eUniformBuffer, DescriptorType::eStorageBuffer},
                      .push_constant_bytes = sizeof(gpu::LatticeCostsPush),
                      .local_size = {kGroupSize, 1, 1},
                      .specialization = specialization}));
  ASSIGN_OR_RETURN(
      gpu::ComputeKernel cells,
      gpu::ComputeKernel::Create(
          *context_,
          {.name = "lattice_costs_cells",
           .spirv = kLatticeCostsCellsSpv,
           .bindings = {DescriptorType::eUniformTexelBuffer, DescriptorType::eUniformBuffer,
                        DescriptorType::eStorageBuffer, DescriptorType::eStorageBuffer},
           .push_constant_bytes = sizeof(gpu::LatticeCostsPush),
           .local_size = {kGroupSize, 1, 1},
           .specialization = specialization}));
  auto kernels = std::make_unique<Kernels>(Kernels{std::move(rows), std::move(cells)});
  return kernels_.emplace(tf_points, std::move(kernels)).first->second.get();
}

Result<LatticeCosts> LatticeCostsGpu::Evaluate(const GpuVolume& volume, const Lattice& lattice,
                                               const TransferFunction& tf, double* gpu_ms) const {
  const auto& g = lattice.grid();
  if (volume.geometry().dims != lattice.geometry().dims) {
    return absl::InvalidArgumentError("lattice was built for a volume of other dimensions");
  }
  const auto& d = volume.geometry().dims;
  const size_t n = static_cast<size_t>(lattice.size());
  const std::vector<Chunk> chunks = ChunksOf(lattice, g[0], d[1], partials_budget_bytes_);
  size_t partial_count = 0;
  for (const Chunk& c : chunks) {
    partial_count = std::max(partial_count, size_t(g[0] * d[1] * (c.z1 - c.z0)));
  }
  ASSIGN_OR_RETURN(gpu::GpuBuffer ubo, UploadTransferFunction(*context_, tf));
  ASSIGN_OR_RETURN(const Kernels* kernels, KernelsFor(int(tf.points().size())));
  ASSIGN_OR_RETURN(const gpu::ComputeKernel rows, volume.KernelFor(*context_, kernels->rows));
  ASSIGN_OR_RETURN(const gpu::ComputeKernel cells, volume.KernelFor(*context_, kernels->cells));
  ASSIGN_OR_RETURN(gpu::GpuBuffer partials,
                   gpu::GpuBuffer::Create(*context_, partial_count * sizeof(glm::vec2),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  ASSIGN_OR_RETURN(gpu::GpuBuffer out,
                   gpu::GpuBuffer::Create(*context_, n * sizeof(glm::vec4),
                                          vk::BufferUsageFlagBits::eStorageBuffer));
  const glm::dvec3& s = volume.geometry().spacing_mm;
  gpu::LatticeCostsPush push{
      .dims = glm::ivec4(d[0], d[1], d[2], 0),
      .grid = glm::ivec4(g[0], g[1], g[2], 0),
      .inv_two_spacing = glm::vec4(float(1.0 / (2.0 * s.x)), float(1.0 / (2.0 * s.y)),
                                   float(1.0 / (2.0 * s.z)), 0.0f),
      .chunk = glm::ivec4(0)};
  ASSIGN_OR_RETURN(gpu::ComputeBatch batch,
                   gpu::ComputeBatch::Begin(*context_, uint32_t(2 * chunks.size())));
  for (const Chunk& c : chunks) {
    push.chunk = glm::ivec4(c.z0, c.z1, c.cz0, c.cz1);
    // The batch puts a full compute barrier between dispatches: the cell
    // pass reads what the row pass wrote, the next row pass overwrites it.
    RETURN_IF_ERROR(batch.Dispatch(rows, {volume.texel_view(), &ubo, &partials}, push,
                                   Groups(uint64_t(g[0]) * d[1] * (c.z1 - c.z0)), "rows"));
    RETURN_IF_ERROR(batch.Dispatch(cells, {volume.texel_view(), &ubo, &partials, &out},
                                   push, Groups(uint64_t(g[0]) * g[1] * (c.cz1 - c.cz0)), "cells"));
  }
  ASSIGN_OR_RETURN(auto timings, batch.SubmitAndWait());
  if (gpu_ms != nullptr) {
    *gpu_ms = 0.0;
    for (const gpu::DispatchTiming& t : timings) *gpu_ms += t.gpu_ms;
  }
  std::vector<glm::vec4> raw(n);
  RETURN_IF_ERROR(out.DownloadSpan(std::span<glm::vec4>(raw)));
  LatticeCosts costs = LatticeCosts::Zeros(n);
  for (size_t i = 0; i < n; ++i) {
    costs.ci_cell[i] = raw[i].x;
    costs.g_cell[i] = raw[i].y;
    costs.ci_point[i] = raw[i].z;
    costs.g_point[i] = raw[i].w;
  }
  return costs;
}

}  // namespace vpm

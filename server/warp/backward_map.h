// The backward map of docs/ALGORITHM.md section 7 on the GPU (docs/WARP.md): for
// a grid of M points over the image box, the rest position of each point
// found through the deformed tet that contains it, kept in an RGBA32F 3D
// image that the warp and the ray caster sample (shaders/backward_map.glsl).
// Kernels: shaders/backward_map.comp (owners, per tet) and
// backward_map_write.comp (values, per grid point). CPU reference:
// BackwardMapCpu.
//
// Updates are incremental: only the tets that moved since the previous
// update, and the unmoved tets whose boxes meet the moved ones' previous
// boxes, are rasterized again, with the result of a full rebuild bit for bit
// (tests/warp/backward_map_test.cc).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/gpu/shader_interface.h"
#include "server/warp/backward_map_values.h"
#include "server/warp/tet_grid_boxes.h"
#include "server/volume/volume.h"

namespace vpm {

class BackwardMap {
 public:
  struct Options {
    // M grid points per axis, each >= 2; 0 on every axis: the default,
    // DefaultBackwardMapDims (ceil(n / 4), at most 64); the volume's dims: the exact map
    // (one point per voxel centre).
    std::array<int64_t, 3> map_dims{0, 0, 0};
    double eps = kBackwardMapEps;  // barycentric tolerance
    // Bytes per values slab; 0: the device's storage-buffer range (128 MiB
    // on lavapipe). Smaller values force more slabs (for tests).
    int64_t max_slab_bytes = 0;
    // Update rebuilds (fills, then every tet; no clear pass) when more than
    // this fraction of the tets moved: the same map, cheaper than clearing
    // nearly every tet (docs/WARP.md). 1: never (tests of the clear pass).
    double full_rebuild_moved_fraction = 0.5;
    // Update only: a vertex whose rest and deformed positions are each
    // within this distance (mm, per axis) of those the map was last built
    // with keeps them; the map is then exactly that of a mesh whose vertices
    // lie within the tolerance of the given ones, and a drag step redoes the
    // tets near the grab instead of nearly all (docs/WARP.md). 0: exact.
    double move_tolerance_mm = 0.0;
  };

  struct UpdateStats {
    bool full_rebuild = false;
    int64_t moved_tets = 0;      // tets whose corners changed (or listed by the caller)
    int64_t processed_tets = 0;  // rasterized: the moved ones and those whose boxes meet theirs
    int64_t held_vertices = 0;   // moved by less than move_tolerance_mm: kept where they were
    // The grid points whose values the update may have changed (the whole
    // grid on a rebuild; empty when none): every other point kept its value
    // bit for bit.
    GridBox changed;
    double gpu_ms = 0.0;         // GPU time of the passes (timestamps; -1 without)
    std::vector<gpu::DispatchTiming> passes;  // clear (updates only), claim, write
    // GPU time of the copy of the changed box into the image (timestamps;
    // recorded in the passes' submit), not in `passes` nor gpu_ms.
    double copy_ms = 0.0;
  };

  // `geometry`: the volume the map belongs to (at least 2 voxels per axis).
  // The new map is the identity (every point outside, displacement 0).
  // Errors: InvalidArgument for bad dims or eps; FailedPrecondition when the
  // device cannot filter RGBA32F 3D images linearly; ResourceExhausted when
  // the grid exceeds the device's image or storage-buffer limits (owners in
  // one binding, values in up to 4).
  static Result<BackwardMap> Create(const gpu::GpuContext& context, const VolumeGeometry& geometry,
                                    const Options& options);
  static Result<BackwardMap> Create(const gpu::GpuContext& context,
                                    const VolumeGeometry& geometry) {
    return Create(context, geometry, Options{});
  }

  // Rasterizes the map for the mesh in its deformed state.
  //   rest_mm      #V by 3, rest positions (mm, physical voxel space)
  //   deformed_mm  #V by 3, deformed positions (mm)
  //   tets         #T by 4 vertex indices
  // Update redoes the tets with a vertex whose rest or deformed position
  // differs from the previous update (everything the first time, or when
  // the tets or the vertex count changed), plus the unmoved tets whose
  // boxes meet their previous boxes. UpdateListed trusts the caller's
  // `moved_tets` (indices into tets) instead: a tet not listed must have
  // the rest and deformed positions of the previous update. Rebuild redoes
  // every tet. All three give the same map (Update: with
  // Options::move_tolerance_mm 0).
  // UpdateStats::held_vertices counts the vertices Update kept at their
  // previous positions (within the tolerance).
  // Errors (InvalidArgument: sizes, indices out of range, non-finite
  // positions) are returned before anything is uploaded or dispatched; the
  // map then keeps its previous content.
  Result<UpdateStats> Update(std::span<const glm::dvec3> rest_mm,
                             std::span<const glm::dvec3> deformed_mm,
                             std::span<const std::array<int32_t, 4>> tets);
  Result<UpdateStats> UpdateListed(std::span<const glm::dvec3> rest_mm,
                                   std::span<const glm::dvec3> deformed_mm,
                                   std::span<const std::array<int32_t, 4>> tets,
                                   std::span<const int32_t> moved_tets);
  Result<UpdateStats> Rebuild(std::span<const glm::dvec3> rest_mm,
                              std::span<const glm::dvec3> deformed_mm,
                              std::span<const std::array<int32_t, 4>> tets);

  // The map: RGBA32F, M texels, (X(p) - p mm, inside); sample it with its
  // linear_sampler() through backward_map.glsl.
  const gpu::GpuImage3D& image() const { return device_.image; }
  // The same values, vec4 per grid point, x fastest, in one buffer usable as
  // a storage or uniform texel buffer (RGBA32F), when the map fits one
  // storage binding (128 MiB on lavapipe); nullptr when it is split in slabs.
  const gpu::GpuBuffer* values_buffer() const {
    return device_.values.size() == 1 ? &device_.values.front() : nullptr;
  }
  const std::array<int64_t, 3>& dims() const { return dims_; }
  glm::dvec3 extent_mm() const { return geometry_.extent_mm(); }
  const VolumeGeometry& geometry() const { return geometry_; }
  // One grid point per voxel: the warp reads the map without interpolation.
  bool exact() const { return dims_ == geometry_.dims; }

  Result<BackwardMapValues> Download() const;

 private:
  enum class Scope { kChanged, kListed, kAll };
  // What the host last sent, to find what changed; valid=false forces a rebuild.
  struct HostState {
    bool valid = false;
    std::vector<glm::dvec3> rest_mm, deformed_mm;
    std::vector<std::array<int32_t, 4>> tets;
    std::vector<GridBox> boxes;  // per tet, the box it was last rasterized in
    // Per tet its 4 vec4 of TetDisplacementFrame, as last uploaded.
    std::vector<glm::vec4> frames;
  };

  // The map's GPU objects, in dependency order.
  struct Device {
    gpu::ComputeKernel kernel;        // backward_map.comp: clear, claim
    gpu::ComputeKernel write_kernel;  // backward_map_write.comp
    gpu::GpuImage3D image;
    gpu::GpuBuffer owner;  // per grid point: the owning tet, or 0xFFFFFFFF
    // Per grid point the value (vec4, x fastest), in slabs of whole z slices
    // of slab_points points each (a storage binding spans 128 MiB at most).
    std::vector<gpu::GpuBuffer> values;
    uint32_t slab_points = 0;
  };

  BackwardMap(const gpu::GpuContext& context, const VolumeGeometry& geometry,
              std::array<int64_t, 3> dims, const Options& options, Device device)
      : context_(&context),
        geometry_(geometry),
        dims_(dims),
        eps_(options.eps),
        full_rebuild_moved_fraction_(options.full_rebuild_moved_fraction),
        move_tolerance_mm_(options.move_tolerance_mm),
        device_(std::move(device)) {}

  Result<UpdateStats> Apply(std::span<const glm::dvec3> rest_mm,
                            std::span<const glm::dvec3> deformed_mm,
                            std::span<const std::array<int32_t, 4>> tets, Scope scope,
                            std::span<const int32_t> moved_tets);
  // The passes of one update: per tet its box now, the work list (moved
  // tets first, `cleared` of them), and the grid box whose values change.
  struct Plan {
    std::vector<GridBox> boxes;
    std::vector<gpu::BackwardMapTetWork> work;  // per tet and slab of z-slices
    uint32_t cleared = 0;                       // work items of moved tets (first)
    int64_t listed_tets = 0;
    GridBox changed;
  };

  Plan PlanWork(std::span<const glm::dvec3> deformed_mm,
                std::span<const std::array<int32_t, 4>> tets, bool full,
                const std::vector<int32_t>& moved) const;
  const gpu::ComputeKernel& kernel() const { return device_.kernel; }
  std::vector<int32_t> ChangedTets(std::span<const glm::dvec3> rest_mm,
                                   std::span<const glm::dvec3> deformed_mm,
                                   std::span<const std::array<int32_t, 4>> tets) const;
  // Recomputes the frames (state_.frames) of the `moved` tets (every tet
  // when `full`) and uploads positions, frames, work (and tets when full).
  Status Upload(std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
                std::span<const std::array<int32_t, 4>> tets, bool full,
                std::span<const int32_t> moved, std::span<const gpu::BackwardMapTetWork> work);
  // Records the passes (full: a fill instead of the clear pass), then the
  // write pass over `changed` and the copy of `changed` into the image, and
  // submits them at once.
  Result<std::vector<gpu::DispatchTiming>> Run(bool full, uint32_t listed, uint32_t moved,
                                               const GridBox& changed);
  Status RecordCopyToImage(gpu::ComputeBatch& batch, const GridBox& box) const;
  // Update with a tolerance: the positions the update uses (held_rest,
  // held_deformed), where each vertex whose rest and deformed positions are
  // within move_tolerance_mm_ of the previous update's keeps those; returns
  // how many it kept.
  int64_t HoldSmallMoves(std::span<const glm::dvec3> rest_mm,
                         std::span<const glm::dvec3> deformed_mm,
                         std::vector<glm::dvec3>& held_rest,
                         std::vector<glm::dvec3>& held_deformed) const;
  // The tets an update redoes: every one on a full rebuild, the caller's
  // (kListed), else those whose corners changed; turns stats.full_rebuild on
  // when more than full_rebuild_moved_fraction_ of the tets moved.
  std::vector<int32_t> MovedTets(std::span<const glm::dvec3> rest_mm,
                                 std::span<const glm::dvec3> deformed_mm,
                                 std::span<const std::array<int32_t, 4>> tets, Scope scope,
                                 std::span<const int32_t> moved_tets, UpdateStats& stats) const;
  // Uploads the plan and runs its passes; their GPU times into stats.
  Status RunPlan(std::span<const glm::dvec3> rest_mm, std::span<const glm::dvec3> deformed_mm,
                 std::span<const std::array<int32_t, 4>> tets, const std::vector<int32_t>& moved,
                 const Plan& plan, UpdateStats& stats);

  const gpu::GpuContext* context_;
  VolumeGeometry geometry_;
  std::array<int64_t, 3> dims_;
  double eps_;
  double full_rebuild_moved_fraction_;
  double move_tolerance_mm_;
  Device device_;
  // Grown on demand; created (1 element) with the map so every binding is
  // valid. previous_buffer_ holds the deformed positions of the last update
  // (the clear pass walks the moved tets there); the two swap per update.
  std::optional<gpu::GpuBuffer> tets_buffer_, deformed_buffer_, previous_buffer_, frames_buffer_,
      work_buffer_;
  HostState state_;
};

}  // namespace vpm

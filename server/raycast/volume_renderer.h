// Renders frames of a (deformed) volume on the GPU: owns the ray-casting
// kernels (pipelines built once), the per-volume brick min-max grid (built
// once per volume), the lookup table (rebaked when the preset or the step
// changes), and the frame buffers. One frame = one command buffer: occupancy
// (when skipping), ray cast, upscale (interactive), then readback and the
// overlay on the CPU; a still frame larger than Options::still_band_rays is
// cast in bands of rows, submitted in groups of about Options::still_band_ms
// each. Render is serialised by a mutex;
// one renderer per session is the intended use (the server's sessions each
// have one).
//
// CPU reference: RenderReference() in raycast_cpu.h.
#pragma once

#include <array>
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "server/common/status.h"
#include "server/gpu/compute_batch.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"
#include "server/raycast/preintegrated_lut_cache.h"
#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"

namespace vpm {

// How the ray caster reads the source volume: a uniform texel buffer with
// manual trilinear interpolation (GpuVolume::texel_view), or a 3D image
// through a linear sampler (GpuVolume::Image, request.volume_image).
enum class VolumeAccess { kTexelBuffer, kSampler3D };

// Still frames are cast in bands of about this many rays (interleaved rows
// of 8 x 8 tiles, gpu::RaycastBandPush), one submit and wait each, or more
// bands where the last still says such a band takes longer than
// kStillBandMs. Vulkan runs a queue's submits in order, so a frame that
// another session submits while a still is being cast runs after the band
// in progress, not after the whole still, and a cancelled still stops after
// it (docs/RENDERING.md, "Stills in bands"): a 512^2 still is at least 8
// bands, a 256^2 one at least 2. Interactive frames are never cut.
inline constexpr int64_t kStillBandRays = 32768;

// After band 0, which goes with the frame's first submit, the other bands of
// a still go in submits of as many bands as fit in about this many ms at
// band 0's time (GPU timestamps; wall time where the device has none): one
// band per submit where a band takes 15 ms or more (lavapipe at 512^2). A
// still that the renderer's last still says takes under half of it is cast
// whole (a discrete GPU): a fast device pays neither a submit per band nor
// dispatches too small to fill it.
inline constexpr double kStillBandMs = 15.0;

class VolumeRenderer {
 public:
  struct Options {
    VolumeAccess volume_access = VolumeAccess::kTexelBuffer;
    int64_t still_band_rays = kStillBandRays;  // 0: a still in one submit
    double still_band_ms = kStillBandMs;       // 0: one submit per band
    // The threads the device splits a dispatch among, which the ray cast
    // lays its rows of tiles out for (gpu::RaycastBandPush); 0: the
    // device's (gpu::DispatchThreads). Any value gives the same pixels.
    uint32_t dispatch_threads = 0;
  };

  static Result<std::unique_ptr<VolumeRenderer>> Create(const gpu::GpuContext& context,
                                                        const Options& options);

  // Errors: InvalidArgument for a bad request (size outside 1..4096, camera
  // not finite, no volume, missing volume_image for kSampler3D, a backward
  // map of another format or under 2 points per axis, bad preset, window or
  // step); Vulkan failures as Internal / ResourceExhausted.
  Result<Frame> Render(const RenderRequest& request);

  // Drops the cached brick grid of `volume`. Call it before freeing a
  // GpuVolume whose address a later volume may reuse; the cache also
  // checks the buffer handle and extent, and holds at most 4 volumes.
  void ForgetVolume(const GpuVolume* volume);

  // The ray cast time (ms) of a still of `rays` rays at the cost per ray of
  // this renderer's last still or rung (a rung, at twice the step, costs
  // less per ray); -1 before the first. Thread-safe.
  double PredictStillMs(int64_t rays) const;

  VolumeAccess volume_access() const { return options_.volume_access; }

 private:
  // What the occupancy buffer was computed for.
  struct OccupancyKey {
    const GpuVolume* volume;
    vk::Buffer volume_buffer;
    RenderMode mode;
    uint64_t lut_generation;
    glm::ivec3 brick_voxels;
    const gpu::GpuImage3D* map;
    uint64_t map_version;
    bool operator==(const OccupancyKey&) const = default;
  };

  struct BrickGrid {
    const GpuVolume* volume;
    glm::ivec3 brick_voxels;          // per side, x y z
    vk::Buffer buffer;                // the volume's texel buffer, to detect reuse
    std::array<uint32_t, 3> extent;
    gpu::GpuBuffer minmax;            // vec2 per brick
  };

  VolumeRenderer(const gpu::GpuContext& context, const Options& options);
  Status Init();
  // The kernels (pipelines built once) and the buffers every frame uses.
  Status CreateKernels();
  Status CreateBuffers();
  Status CheckGpuInputs(const RenderRequest& request) const;
  // The volume's brick min-max grid for bricks of `brick_voxels` per side,
  // computed on first use and cached.
  Result<const gpu::GpuBuffer*> BrickMinMax(const GpuVolume& volume, glm::ivec3 brick_voxels);
  // Bakes and uploads the preset's table for the step (and, when asked, its
  // pre-integrated table) unless they are there already.
  Status PrepareLut(const RenderPreset& preset, double step_mm, bool preintegrated);
  Status EnsureBuffer(std::optional<gpu::GpuBuffer>& buffer, vk::DeviceSize bytes,
                      vk::BufferUsageFlags usage);
  Status EnsureMapTexels(size_t points);
  Status EnsureOccupancy(size_t bricks);
  // The bricks whose occupancy a frame recomputes: from lo, size per axis
  // (a zero size: none, the cached occupancy holds).
  struct BrickBox {
    glm::ivec3 lo{0};
    glm::ivec3 size{0};
    bool empty() const { return size.x <= 0 || size.y <= 0 || size.z <= 0; }
    int64_t count() const { return empty() ? 0 : int64_t(size.x) * size.y * size.z; }
  };
  // The bricks whose occupancy (brick_occupancy.comp) reads a map grid
  // point of the box lo..hi (inclusive); map_dims: M per axis.
  static BrickBox BricksMeetingMapBox(const gpu::RaycastParams& p,
                                      const std::array<int, 3>& map_dims, const glm::ivec3& lo,
                                      const glm::ivec3& hi);
  // The frame's ray caster (specialized for the volume) and its arguments,
  // resolved once for all its bands. map_view: the map's texels it reads.
  struct Cast {
    gpu::ComputeKernel kernel;
    std::array<gpu::KernelArg, 7> args;
  };
  Result<Cast> PrepareCast(const RenderRequest& request, const RaycastSetup& setup,
                           vk::BufferView map_view);
  // Records the frame's first submit: the map copy and occupancy pass as
  // needed, the ray cast of band 0 of `bands`, and the upscale (interactive
  // frames, always one band). map_view: the map's texels the kernels read.
  Status RecordFrame(gpu::ComputeBatch& batch, const RenderRequest& request,
                     const RaycastSetup& setup, const gpu::GpuBuffer& minmax, bool upscale,
                     const BrickBox& occupancy_box, vk::BufferView map_view, const Cast& cast,
                     int bands);
  // Records the ray cast of band `band` of `bands`: the rows of 8 x 8 tiles
  // band, band + bands, ... (gpu::RaycastBandPush).
  Status RecordBand(gpu::ComputeBatch& batch, const Cast& cast, const RaycastSetup& setup,
                    int band, int bands);
  // Bands for a frame cast at width x height: still frames width x height /
  // still_band_rays, or as many as make bands of still_band_ms at the last
  // still's cost per ray where that is more (at least 1, at most a tile row
  // each), or 1 where that cost says this one takes under still_band_ms / 2;
  // others 1.
  int Bands(const RenderRequest& request, int width, int height) const;
  // Bands per submit after band 0, from band 0's time (ms): still_band_ms
  // worth, at least 1, at most bands - 1.
  int BandsPerSubmit(double band0_ms, int bands) const;
  // A still's ray cast time per ray (its bands' GPU timestamps summed, else
  // submits_ms, the wall time of its submits), for the next still's Bands.
  void RememberStillCost(std::span<const gpu::DispatchTiming> timings, double submits_ms,
                         size_t rays);
  // A uniform-texel view of the caller's map values (request.
  // backward_map_texels) for `points` grid points; InvalidArgument when the
  // buffer is too small or the device cannot view that many texels.
  Result<vk::raii::BufferView> CallerMapView(const RenderRequest& request, size_t points) const;
  // What this frame's occupancy pass does. key: what the occupancy depends
  // on (volume, table, mode, bricks, map; a map's content is known unchanged
  // only through backward_map_version); box: the bricks to compute, none
  // when the last pass's (occupancy_key_) is of key (current), those that
  // the map's last update touched when it is of the map's previous version,
  // else all.
  struct OccupancyPlan {
    OccupancyKey key;
    bool cacheable = false;  // no map, or a versioned one
    bool current = false;
    BrickBox box;
  };
  OccupancyPlan PlanOccupancy(const RenderRequest& request, const gpu::RaycastParams& p,
                              const std::array<int, 3>& map_dims) const;
  // Submits the frame's first batch (`batch`, recorded), then a still's
  // other bands; caches the occupancy once its pass has run and remembers a
  // still's cost. `submits`: the submits made. Returns their timings.
  Result<std::vector<gpu::DispatchTiming>> SubmitFrame(gpu::ComputeBatch& batch,
                                                       const RenderRequest& request,
                                                       const RaycastSetup& setup, const Cast& cast,
                                                       const OccupancyPlan& occupancy, int bands,
                                                       int& submits);
  // With a backward map: the caller's map values viewed (CallerMapView;
  // created per frame, microseconds, so that it never outlives the buffer),
  // or the renderer's own copy sized (EnsureMapTexels) and a null view.
  Result<vk::raii::BufferView> PrepareMapTexels(const RenderRequest& request,
                                                const std::array<int, 3>& map_dims);
  // A still's bands 1 .. bands - 1, BandsPerSubmit(band0_ms) to a submit
  // (between two submits runs what another renderer submits), their timings
  // appended; stops at request.cancel. Returns the submits it made.
  Result<int> SubmitOtherBands(const RenderRequest& request, const Cast& cast,
                               const RaycastSetup& setup, int bands, double band0_ms,
                               std::vector<gpu::DispatchTiming>& timings);
  // Fills frame's kernel timings, pixels (the upscaled buffer when
  // `upscale`) and, with settings.count_samples, its samples and occupied
  // bricks (frame.total_bricks set).
  Status ReadBack(const RenderRequest& request, const RaycastSetup& setup, bool upscale,
                  std::span<const gpu::DispatchTiming> timings, Frame& frame);

  const gpu::GpuContext* context_;
  Options options_;
  std::mutex mutex_;
  std::optional<gpu::ComputeKernel> minmax_kernel_;
  std::optional<gpu::ComputeKernel> occupancy_kernel_;
  std::optional<gpu::ComputeKernel> raycast_kernels_[2][2];  // [mip][backward map]
  std::optional<gpu::ComputeKernel> cell_gradient_kernels_[2];  // DVR [backward map]
  std::optional<gpu::ComputeKernel> preintegrated_kernels_[2];  // the same, pre-integrated
  std::optional<gpu::ComputeKernel> upscale_kernel_;
  std::optional<gpu::GpuImage3D> identity_map_;  // 2^3 zeros, bound when there is no map
  // The backward map copied per frame for the texel-buffer variants (RGBA32F,
  // vkCmdCopyImageToBuffer: 2-3x faster than a copy kernel on lavapipe).
  std::optional<gpu::GpuBuffer> map_texels_;
  vk::raii::BufferView map_texels_view_{nullptr};  // after the buffer it views
  std::optional<gpu::GpuBuffer> params_;          // RaycastParams, storage
  // RenderLutBlock, read by the ray casters through an RGBA32F texel view
  // (a gather per fetch on lavapipe; as a uniform block indexed per sample
  // the composite still cost 7-10% more, docs/RENDERING.md).
  std::optional<gpu::GpuBuffer> lut_;
  vk::raii::BufferView lut_view_{nullptr};  // after the buffer it views
  std::optional<gpu::GpuBuffer> nonzero_prefix_;  // int per entry + 1, storage
  std::optional<gpu::GpuBuffer> stats_;           // sample counter, storage
  // Float per brick: written as storage, read by the ray casters through a
  // uniform texel view (a gather on lavapipe, where a storage-buffer load
  // at a per-lane index is a loop over the lanes).
  std::optional<gpu::GpuBuffer> occupancy_;
  vk::raii::BufferView occupancy_view_{nullptr};  // after the buffer it views
  std::optional<gpu::GpuBuffer> pixels_;          // ray-cast RGBA8, storage
  std::optional<gpu::GpuBuffer> upscaled_;        // interactive output, storage
  std::vector<BrickGrid> brick_grids_;
  std::optional<RenderPreset> lut_preset_;
  double lut_step_mm_ = 0.0;
  glm::vec4 lut_params_{0.0f};
  uint64_t lut_generation_ = 0;  // bumped at every bake
  bool preintegrated_baked_ = false;  // the buffer holds the pre-integrated table of lut_preset_
  PreintegratedLutCache preintegrated_tables_;  // uploaded to lut_ after its RenderLutBlock
  std::optional<OccupancyKey> occupancy_key_;
  // The last still's or rung's (RememberStillCost); -1: none yet. Atomic:
  // PredictStillMs reads it outside mutex_.
  std::atomic<double> still_ms_per_ray_{-1.0};
};

}  // namespace vpm

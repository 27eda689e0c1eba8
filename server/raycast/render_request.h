// What one frame asks for (RenderRequest) and what comes back (Frame), plus
// the translation of a request into the ray caster's parameter block, shared
// by the GPU renderer and the CPU reference so that both cast the same rays.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_image3d.h"
#include "server/gpu/shader_interface.h"
#include "server/raycast/camera.h"
#include "server/raycast/clip_region.h"
#include "server/raycast/overlay.h"
#include "server/raycast/render_presets.h"
#include "server/volume/gpu_volume.h"
#include "server/volume/volume.h"

namespace vpm {

enum class RenderMode { kDvr, kMip };

// kStill: full resolution, step 0.5 x the smallest spacing for DVR
// (RenderPreset::still_step_factor: 1.0 for ct-soft-tissue), 1.0 for MIP.
// kInteractive: as RenderRequest::interactive says (InteractiveCast).
enum class RenderQuality { kStill, kInteractive };

// How an interactive frame is cast: rays on a grid `divisor` times coarser
// than the frame per axis (ceil(side / divisor) rays; upscaled on the GPU by
// upscale_filter, gpu::kUpscaleBilinear or gpu::kUpscaleCatmullRom), at the
// pixel-footprint step of that grid (InteractiveStepMm) but, where
// still_step_multiple > 0, no coarser than still_step_multiple x the still's
// step (RequestStepMm of the same request as a still): on coarse volumes the
// footprint's floor, one voxel, is what PSNR against the still loses most to
// (docs/RENDERING.md, "Interactive quality").
struct InteractiveCast {
  double divisor = 2.0;  // 1..kMaxInteractiveDivisor
  double still_step_multiple = 0.0;
  int upscale_filter = gpu::kUpscaleBilinear;
};
inline constexpr double kMaxInteractiveDivisor = 4.0;

// What the user chooses for frames while interacting, speed against
// sharpness (docs/RENDERING.md, "Interactive quality", measures each):
// kFast: half resolution, footprint step, bilinear upscale (the highest
// frame rate); kBalanced: half resolution, step at most 2 x the still's;
// kSharp: full resolution, step at most 1.5 x the still's (at least 35 dB
// on the phantom and the kidney CT, at a fraction of the frame rate). The
// ray starts are jittered with a new seed per frame (DeformableScene).
// kAuto: the device's choice, resolved where the device is known
// (AutoInteractiveQuality in deformable_scene.h): kSharp on a discrete GPU,
// kFast on others; InteractiveCastFor, which knows no device, gives kAuto
// kFast's cast.
enum class InteractiveQuality { kFast, kBalanced, kSharp, kAuto };
inline constexpr InteractiveQuality kDefaultInteractiveQuality = InteractiveQuality::kAuto;
InteractiveCast InteractiveCastFor(InteractiveQuality quality);
// The quality a client's flag names: "auto", "fast", "balanced" or
// "sharp"; nullopt for any other name.
std::optional<InteractiveQuality> InteractiveQualityNamed(std::string_view name);

inline constexpr int kMaxFrameSide = 4096;
// Empty-space-skipping bricks are sized in mm, not voxels, so that a ray
// crosses as many bricks (and the occupancy pass, rerun whenever the map
// changes, visits as many) on a 512 x 512 x 900 CT of 0.74 x 0.74 x 0.27 mm
// as on the 256^3 phantom of 1.48 x 1.48 x 0.95 mm: the skip costs the same
// per pixel whatever the slice count. Per axis, w = round(brick mm /
// spacing) voxels, at least 1 (BrickVoxels). On the phantom: 4 x 4 x 6
// voxels still, 8 x 8 x 13 interactive (docs/RENDERING.md, "Empty-space
// skipping", for the measurements behind both sizes).
inline constexpr double kStillBrickMm = 6.0;
inline constexpr double kInteractiveBrickMm = 12.0;
// Frames stepping at least this far (mm) skip by kInteractiveBrickMm bricks
// whatever their quality: a still brick would hold 4 samples or fewer, and
// walking twice as many bricks costs more than the samples they skip (the
// phantom's still MIP at 2 mm 88 -> 73 ms, its composite at 3 mm 87 -> 84
// ms; docs/RENDERING.md, "Empty-space skipping").
inline constexpr double kCoarseGridStepMm = 1.5;
inline constexpr double kStillMipStepFactor = 1.0;
// Still steps are also no coarser than these (mm), whatever the voxels: on
// the 3 mm kidney CT, the presets' factors gave steps of 1.5 (DVR) and 3 mm
// (MIP), whose stills measured 28.6-37.9 dB (DVR, shaded bone and vessel
// presets) and 33.4 dB (MIP) against step / 8; at these caps every preset
// holds 40 dB on that CT and the phantom (docs/RENDERING.md, "Sampling";
// bench/step_psnr_bench.cc).
inline constexpr double kStillMaxStepMm = 0.375;
inline constexpr double kStillMipMaxStepMm = 0.75;
// Interactive frames step by what the screen can show, not by the voxels:
// half the footprint of one ray-cast pixel at the orbit centre
// (kInteractiveStepPerPixel, Nyquist for what a pixel resolves), at least
// kInteractiveStepFactor x the smallest spacing and at most the box diagonal
// / kInteractiveMinSamplesPerRay (InteractiveStepMm; docs/RENDERING.md,
// "Quality modes").
inline constexpr double kInteractiveStepFactor = 1.0;
inline constexpr double kInteractiveStepPerPixel = 0.5;
inline constexpr double kInteractiveMinSamplesPerRay = 256;
// Longest ray, in samples, a request may ask for (the box diagonal / step):
// bounds a frame's work on any device (a GPU watchdog kills long dispatches).
inline constexpr double kMaxSamplesPerRay = 32768;

struct RaycastSettings {
  bool empty_space_skipping = true;
  bool early_termination = true;  // DVR: stop when opacity > 0.99; MIP: at the window's white
  bool shading = true;            // DVR gradient shading (Blinn-Phong headlight)
  double step_mm = 0.0;           // 0: the quality's default
  glm::dvec3 background{0.0};     // rgb in [0, 1]
  double ambient = 0.35;
  double diffuse = 0.65;
  double specular = 0.25;
  double shininess = 24.0;
  // Count the samples taken (GPU: one atomic add per pixel), for tests.
  bool count_samples = false;
  // Interactive DVR frames shade with the gradient of the trilinear cells
  // each sample reads (chain rule through the map; no extra reads) instead
  // of central differences of J (6 more reads per shaded sample): the
  // interactive soft-tissue cast 29 -> 17 ms, measured error in
  // docs/RENDERING.md ("Quality modes").
  bool interactive_cell_gradient = true;
  // The same for still DVR frames: the 512x512 soft-tissue still about
  // halves (GPU 563 -> 276 ms in one run), at 33-37 dB PSNR against the taps
  // (docs/RENDERING.md, "Quality modes"); false: the central-difference taps.
  bool still_cell_gradient = true;
  // Each ray's first sample moved on by a fraction of the step in [0, 1),
  // from a hash of its pixel and jitter_seed (ray_start_jitter.h): samples of
  // neighbouring rays at unrelated depths, so the step shows as fine noise
  // instead of rings ("wood grain") on surfaces (docs/RENDERING.md,
  // "Sampling"). One seed, one picture: keep the seed for stills, change it
  // per interactive frame (DeformableScene does).
  bool jitter = true;
  uint32_t jitter_seed = 0;
  // DVR with the cell gradient: each step composited as a segment whose
  // value runs from the previous sample's to this one's, through the
  // pre-integrated table (preintegrated_lut.h), so that sharp transfer
  // functions do not depend on where samples land (docs/RENDERING.md,
  // "Sampling"). The tap-gradient loop ignores it.
  bool preintegrated = true;
  // Pre-integrated steps lit by the mean of the light at their two ends
  // (the trapezoid rule) instead of the light at the sample ending them:
  // shaded stills converge faster with the step (docs/RENDERING.md,
  // "Sampling").
  bool light_both_ends = true;
  // Pre-integrated DVR: the step from where a ray enters (the box or the
  // clip region) to its first sample and the one from its last sample to
  // where it leaves, each composited as long as it is. Off, the first
  // sample stands for a whole step of its value and the rest past the last
  // sample is left out, so that a face cut through tissue (the view cut, a
  // crop box, the first and last slices) shows where the jitter put each
  // ray's first sample (docs/RENDERING.md, "Sampling").
  bool partial_end_steps = true;
  // MIP with skipping: a first walk along the ray, taking no sample, finds
  // the brick that can show the most and samples it first; the walk then
  // skips every brick whose maximum is under what it found. The same
  // picture (docs/RENDERING.md, "Empty-space skipping").
  bool mip_brightest_first = true;
  // MIP: after the walk, the peaks around the ray's brightest sample and
  // the next brightest one at least two samples from it are found by a
  // bracketing search between samples (twelve more reads per ray), so that
  // thin bright structures keep their brightness at coarse steps
  // (docs/RENDERING.md, "Sampling").
  bool mip_peak_refine = true;
};

// Raycast flag (RaycastParams::image.z) beside gpu::kRaycast*: shade with
// the cell gradient (the GPU picks the pipeline by it, the CPU reference
// the code path).
inline constexpr int kRaycastCellGradient = 32;
// Raycast flag: composite each step as a segment through the pre-integrated
// table (RaycastSettings::preintegrated; the GPU picks the pipeline by it).
inline constexpr int kRaycastPreintegrated = 128;

struct RenderRequest {
  Camera camera;
  RenderMode mode = RenderMode::kDvr;
  RenderPreset preset;                   // MakeRenderPreset(name, volume)
  std::optional<MipWindow> mip_window;   // default: preset.mip_window
  RenderQuality quality = RenderQuality::kStill;
  // How kInteractive frames are cast (ignored by stills).
  InteractiveCast interactive = InteractiveCastFor(kDefaultInteractiveQuality);
  int width = 512;                       // output pixels, 1..kMaxFrameSide
  int height = 512;
  const GpuVolume* volume = nullptr;     // the source (rest) volume
  // The source volume as a 3D image (GpuVolume::Image); only read when the
  // renderer samples through a sampler3D (VolumeAccess::kSampler3D).
  const gpu::GpuImage3D* volume_image = nullptr;
  // Backward map, R32G32B32A32Sfloat, M grid points corner to corner of the
  // image box, texel = (X(p) - p in mm, inside); null: undeformed.
  const gpu::GpuImage3D* backward_map = nullptr;
  // Nonzero: the map's content is unchanged for as long as this number is
  // (bump it with every update), so the renderer may reuse its per-frame
  // brick occupancy. 0: unknown, recomputed every frame.
  uint64_t backward_map_version = 0;
  // Optional, with backward_map_version: the map's version before its last
  // update, and the box of grid points (inclusive, (0, 0, 0) .. (Mx-1, My-1,
  // Mz-1); empty when lo > hi) outside which that update left every value.
  // A renderer whose occupancy is of that previous version then redoes only
  // the bricks whose map cells meet the box (the same occupancy: a brick
  // reads only the map points of the cells it overlaps). 0: unknown.
  uint64_t backward_map_previous_version = 0;
  glm::ivec3 backward_map_changed_lo{0};
  glm::ivec3 backward_map_changed_hi{-1};
  // Optional: the map's values as a buffer with uniform-texel usage, vec4
  // per grid point, x fastest (BackwardMap::values_buffer()). The
  // texel-buffer ray casters then read it in place instead of copying the
  // image into a buffer of their own every frame (a transfer copy).
  const gpu::GpuBuffer* backward_map_texels = nullptr;
  RaycastSettings settings;
  // What part of the deformed volume shows (world frame); empty: all of it.
  ClipRegion clip;
  OverlayData overlay;
  // Polled between the bands of a still (VolumeRenderer::Render): a still
  // nobody waits for stops after the band in progress. Default: never.
  CancelToken cancel;
};

struct FrameTimings {
  double map_copy_ms = 0.0;   // GPU: backward map to texel buffer
  double occupancy_ms = 0.0;  // GPU: per-frame brick occupancy kernel
  double raycast_ms = 0.0;    // GPU: ray casting kernel
  double upscale_ms = 0.0;    // GPU: interactive upscale
  double render_ms = 0.0;     // sum of the kernels above (GPU timestamps)
  double readback_ms = 0.0;   // wall
  double overlay_ms = 0.0;    // wall
  double wall_ms = 0.0;       // the whole Render call
};

struct Frame {
  std::vector<uint8_t> rgba;  // width * height * 4, row 0 at the top
  int width = 0;
  int height = 0;
  int render_width = 0;       // ray-cast resolution (interactive: about half)
  int render_height = 0;
  double step_mm = 0.0;
  int bands = 1;              // bands the ray cast was cut into (VolumeRenderer: stills)
  int submits = 1;            // submits those bands took (grouped: still_band_ms)
  int64_t samples = -1;       // samples taken, when settings.count_samples
  int64_t occupied_bricks = -1;  // bricks the occupancy pass kept (skipping on)
  int64_t total_bricks = 0;
  bool occupancy_reused = false;  // the occupancy of an earlier frame still held
  // Bricks whose occupancy this frame computed: total_bricks, fewer after a
  // map update that changed part of the map (backward_map_previous_version),
  // 0 when reused or without skipping.
  int64_t occupancy_bricks_computed = 0;
  FrameTimings timings;
};

// Voxels per brick side along x, y, z for a quality on a volume of this
// geometry: round(kStillBrickMm or kInteractiveBrickMm / spacing), clamped
// to [1, max(1, n - 1)].
glm::ivec3 BrickVoxels(RenderQuality quality, const VolumeGeometry& geometry);

// The bricks a request's frame skips by: BrickVoxels of its quality, but
// still bricks for interactive frames cast finer than half resolution
// (InteractiveCast::divisor < 2; the sharp setting): at full resolution on
// the phantom they cast 14% faster than interactive bricks
// (docs/RENDERING.md, "Interactive quality"); and interactive bricks for any
// frame whose step is kCoarseGridStepMm or more.
glm::ivec3 RequestBrickVoxels(const RenderRequest& request, const VolumeGeometry& geometry);

// Brick grid of a volume: ceil((n - 1) / w) bricks per axis (at least 1) for
// bricks of w voxels per side (per axis); brick b spans voxels
// [w b, min(w b + w, n - 1)].
std::array<int, 3> BrickGridDims(const std::array<int64_t, 3>& dims, glm::ivec3 brick_voxels);

struct RaycastSetup {
  gpu::RaycastParams params{};
  int render_width = 0;
  int render_height = 0;
  double step_mm = 0.0;
};

// Checks the request against `geometry` (size, camera, preset, window,
// step, settings; GPU handles are the renderer's business) and fills the
// parameter block but for params.lut (LutParams, once the table for
// setup.step_mm is baked). map_dims: the backward map's grid points,
// {0, 0, 0} for none. Errors: InvalidArgument naming what is wrong.
Result<RaycastSetup> PrepareRaycast(const RenderRequest& request, const VolumeGeometry& geometry,
                                    const std::array<int, 3>& map_dims);

// params.lut for `lut`: (value_lo, entries per value unit, entry count,
// gpu::kPreintegratedEntries).
glm::vec4 LutParams(const RenderLut& lut);

// The step a request will use (validated by PrepareRaycast).
double RequestStepMm(const RenderRequest& request, const VolumeGeometry& geometry);

// Rays a request casts along a frame side of `side` pixels: `side`, or for
// kInteractive ceil(side / interactive.divisor).
int RenderSide(const RenderRequest& request, int side);

// The filter that upscales the request's ray-cast pixels (interactive
// frames: request.interactive.upscale_filter; stills are not upscaled).
int UpscaleFilterOf(const RenderRequest& request);

// The interactive footprint step (mm) for a camera casting render_width x
// render_height rays: max(kInteractiveStepFactor
// x smallest spacing, min(kInteractiveStepPerPixel x pixel footprint at the
// orbit centre, diagonal / kInteractiveMinSamplesPerRay)), the footprint
// being 2 distance tan(fov / 2) / the shorter side.
double InteractiveStepMm(const Camera& camera, int render_width, int render_height,
                         const VolumeGeometry& geometry);

}  // namespace vpm

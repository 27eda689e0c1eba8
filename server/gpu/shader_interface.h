// C++ mirror of shaders/shader_interface.glsl: every push-constant struct and
// uniform block shared with a kernel. Layouts follow std430 (push constants)
// and std140 (uniform blocks); the static_asserts pin the sizes so that a
// change on one side without the other fails to compile.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

namespace vpm::gpu {

// gradient_magnitude.comp
struct GradientPush {
  glm::ivec4 dims;             // (nx, ny, nz, 0) voxels
  glm::vec4 inv_two_spacing;   // (1/(2 sx), 1/(2 sy), 1/(2 sz), 0) 1/mm
};
static_assert(sizeof(GradientPush) == 32);

// transfer_function.comp
struct VoxelMapPush {
  glm::ivec4 dims;  // (nx, ny, nz, 0) voxels
};
static_assert(sizeof(VoxelMapPush) == 16);

// lattice_costs_rows.comp and lattice_costs_cells.comp (step 1, two passes).
struct LatticeCostsPush {
  glm::ivec4 dims;             // (nx, ny, nz, 0) voxels
  glm::ivec4 grid;             // (Gx, Gy, Gz, 0) lattice vertices
  glm::vec4 inv_two_spacing;   // (1/(2 sx), 1/(2 sy), 1/(2 sz), 0) 1/mm
  glm::ivec4 chunk;            // (z0, z1, cz0, cz1): voxel slices and cell layers of this pass
};
static_assert(sizeof(LatticeCostsPush) == 64);

// Uniform block TransferFunctionBlock (std140): control points (value, cost)
// sorted by value in points[i].xy, the slope of the segment ending at point i
// in points[i].z (0 for i = 0 and for steps), count in count.x.
inline constexpr int kMaxTfPoints = 32;
struct TransferFunctionBlock {
  glm::vec4 points[kMaxTfPoints];
  glm::ivec4 count;
};
static_assert(sizeof(TransferFunctionBlock) == 528);

// Ray casting (server/raycast). brick_minmax.comp: one invocation per brick
// of wx x wy x wz cells (bricks share their boundary voxel layer).
struct BrickMinMaxPush {
  glm::ivec4 dims;          // (nx, ny, nz, 0) voxels
  glm::ivec4 bricks;        // (bx, by, bz, 0) bricks
  glm::ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
};
static_assert(sizeof(BrickMinMaxPush) == 48);

// brick_occupancy.comp: per brick of the deformed space, whether (DVR) or up
// to what value (MIP) the source region it samples can contribute.
struct BrickOccupancyPush {
  glm::ivec4 dims;        // (nx, ny, nz, 0) voxels
  glm::ivec4 bricks;        // (bx, by, bz, 0) bricks
  glm::ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
  glm::vec4 spacing_mm;   // (sx, sy, sz, 0)
  glm::vec4 lut;          // (value_lo, entries per value unit, entry count, 0)
  // (mode: 0 DVR / 1 MIP, has_map, box bricks along x, box bricks along y)
  glm::ivec4 flags;
  glm::vec4 map_dims;     // (Mx, My, Mz, 0) backward-map grid points
  // (x, y, z, box bricks along z): the box of bricks the pass updates starts
  // at brick (x, y, z); the others keep their occupancy (a map update that
  // changed part of the map, VolumeRenderer).
  glm::ivec4 box_lo;
};
static_assert(sizeof(BrickOccupancyPush) == 128);

// raycast_*.comp (the body in raycast_body.glsl): uniform block RaycastParams (std140).
// Ray of pixel (px, py): eye + t * normalize(forward + ndc.x * right + ndc.y * up),
// ndc = (2 (px + 0.5) / width - 1, 1 - 2 (py + 0.5) / height).
inline constexpr int kRaycastShading = 1;           // image.z flag bits
inline constexpr int kRaycastSkipping = 2;
inline constexpr int kRaycastEarlyTermination = 4;
inline constexpr int kRaycastHasMap = 8;
inline constexpr int kRaycastCountSamples = 16;
// Ray starts jittered by a fraction of the step from a hash of the pixel and
// image.w, the frame's seed (RaycastJitter in server/raycast/ray_start_jitter.h).
inline constexpr int kRaycastJitter = 64;
// MIP: the brick that can show the most sampled first, so that the walk
// skips every brick that cannot exceed its maximum (docs/RENDERING.md,
// "Empty-space skipping"). 32 and 128 are render_request.h's.
inline constexpr int kRaycastBrightestFirst = 256;
// MIP: the peaks around the ray's brightest sample and the next brightest
// apart from it refined by a bracketing search between samples
// (docs/RENDERING.md, "Sampling").
inline constexpr int kRaycastPeakRefine = 512;
// DVR, pre-integrated: each step lit by the mean of its two ends' light
// (the trapezoid rule), not by its back end's alone (docs/RENDERING.md,
// "Sampling").
inline constexpr int kRaycastLightBothEnds = 1024;
// DVR, pre-integrated: a ray's first and last steps, from where it enters
// to its first sample and from its last sample to where it leaves, each as
// long as it is, not a whole step (docs/RENDERING.md, "Sampling").
inline constexpr int kRaycastPartialEndSteps = 2048;
inline constexpr int kRaycastMaxClipPlanes = 16;  // VPM_RAYCAST_MAX_CLIP_PLANES
struct RaycastParams {
  glm::vec4 eye_mm;      // xyz eye (physical mm); w: step_mm
  glm::vec4 forward;     // xyz unit view direction
  glm::vec4 right;       // xyz camera right * tan(fov/2) * width / shorter side
  glm::vec4 up;          // xyz camera up * tan(fov/2) * height / shorter side
  glm::ivec4 dims;       // (nx, ny, nz, mode: 0 DVR / 1 MIP) voxels
  glm::vec4 spacing_mm;  // (sx, sy, sz, 0)
  glm::ivec4 image;      // (width, height, flags, jitter seed) pixels
  glm::ivec4 bricks;     // (bx, by, bz, 0) bricks
  glm::ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
  glm::vec4 lut;         // (value_lo, entries per value unit, entry count, 0)
  glm::vec4 window;      // MIP (value of black, 1 / window width, value of white, 0)
  glm::vec4 background;  // rgb in [0, 1]
  glm::vec4 shading;     // (ambient, diffuse, specular, shininess)
  glm::vec4 map_dims;    // (Mx, My, Mz, 0) backward-map grid points
  glm::vec4 gradient;    // (|grad| at which shading is half on, value/mm; 0, 0, 0)
  glm::ivec4 clip;       // (planes used, 0, 0, 0)
  // Half spaces of physical space a sample must lie in: xyz unit normal n,
  // w offset d (mm), keeps dot(n, x) >= d (server/raycast/clip_region.h).
  glm::vec4 clip_planes[kRaycastMaxClipPlanes];
};
static_assert(sizeof(RaycastParams) == 256 + 16 * kRaycastMaxClipPlanes);

// RenderLutBlock: colour (rgb) and opacity for the frame's step (a) at
// value_lo + i / (entries per value unit); the ray casters read it as an
// RGBA32F uniform texel buffer, one entry a texel.
inline constexpr int kRenderLutEntries = 1024;
struct RenderLutBlock {
  glm::vec4 entries[kRenderLutEntries];
};
static_assert(sizeof(RenderLutBlock) == 16384);
// The pre-integrated table (server/raycast/preintegrated_lut.h) follows the
// RenderLutBlock in the same texel buffer: N x N entries, N =
// kPreintegratedEntries (RaycastParams::lut.w when the frame uses it).
inline constexpr int kPreintegratedEntries = 256;

// raycast_*.comp: the rows of 8 x 8 tiles a dispatch casts, so that a frame
// may be cast in bands, one submit each (VolumeRenderer::Options::
// still_band_rays). Band b of n takes tile rows b, b + n, b + 2n, ...: each
// band a sample of the whole frame (bands of consecutive rows left one of
// two threads idle for most of a band). t: the threads the device splits a
// dispatch among, one contiguous run of workgroups each (DispatchThreads in
// server/gpu/dispatch_threads.h); the band's rows are dealt out to the runs
// in turn, so that each thread casts a sample of the band.
struct RaycastBandPush {
  glm::ivec4 rows;  // (b, n, t, 0)
};
static_assert(sizeof(RaycastBandPush) == 16);

// upscale.comp: RGBA8 resize, bilinear or Catmull-Rom bicubic.
inline constexpr int kUpscaleBilinear = 0;
inline constexpr int kUpscaleCatmullRom = 1;
struct UpscalePush {
  glm::ivec4 size;    // (source width, source height, target width, target height)
  glm::ivec4 mode;    // (kUpscaleBilinear or kUpscaleCatmullRom, 0, 0, 0)
};
static_assert(sizeof(UpscalePush) == 32);

// backward_map.comp: rasterizes the backward map's owners tet by tet, one
// workgroup per listed tet. pass (in map_dims.w): 0 clear the previous
// coverage of the moved tets, 1 claim (atomicMin of the tet index).
struct BackwardMapPush {
  glm::ivec4 map_dims;  // (mx, my, mz, pass) grid points
  glm::vec4 step_mm;    // (hx, hy, hz, eps): grid step extent/(M-1) mm; barycentric tolerance
  // (listed tets, moved tets (listed first, cleared), 0, 0)
  glm::uvec4 work;
};
static_assert(sizeof(BackwardMapPush) == 48);

// backward_map_write.comp: the value of every grid point of a box from its
// owner's affine frame, one invocation per point.
struct BackwardMapWritePush {
  glm::ivec4 map_dims;  // (mx, my, mz, points per values slab) grid points
  glm::vec4 step_mm;    // (hx, hy, hz, 0): grid step extent/(M-1) mm
  glm::ivec4 box_lo;    // (x, y, z, 0) first grid point of the box
  glm::ivec4 box_hi;    // (x, y, z, 0) last grid point of the box (inclusive)
};
static_assert(sizeof(BackwardMapWritePush) == 64);

// One listed tet of backward_map.comp (std430 storage buffer element): its
// grid-point box at the previous update (pass 0, moved tets only) and now
// (passes 1, 2); inclusive, empty when lo > hi.
struct BackwardMapTetWork {
  glm::ivec4 old_lo;  // (x, y, z, tet index)
  glm::ivec4 old_hi;  // (x, y, z, 0)
  glm::ivec4 new_lo;  // (x, y, z, 0)
  glm::ivec4 new_hi;  // (x, y, z, 0)
};
static_assert(sizeof(BackwardMapTetWork) == 64);

// warp_volume.comp, warp_volume_texel.comp: J(x) = I(X(x)) per voxel.
struct WarpVolumePush {
  glm::ivec4 dims;         // (nx, ny, nz, exact) voxels; exact = 1: one map point per voxel
  glm::vec4 inv_spacing;   // (1/sx, 1/sy, 1/sz, 0) 1/mm
  glm::vec4 spacing_mm;    // (sx, sy, sz, 0) mm
  glm::vec4 extent_mm;     // ((n-1)*s, 0) mm, the image box
  glm::vec4 map_dims;      // (mx, my, mz, 0) backward-map grid points, as floats
};
static_assert(sizeof(WarpVolumePush) == 80);

// slice_volume.comp: J on a plane of pixels (server/raycast/slice_sampler.h).
struct SliceVolumePush {
  glm::ivec4 dims;         // (nx, ny, nz, 0) voxels
  glm::vec4 inv_spacing;   // (1/sx, 1/sy, 1/sz, 0) 1/mm
  glm::vec4 extent_mm;     // ((n-1)*s, 0) mm, the image box
  glm::vec4 map_dims;      // (mx, my, mz, 0) backward-map grid points, as floats
  glm::vec4 origin_mm;     // physical corner of pixel (0, 0), mm
  glm::vec4 step_u_mm;     // one pixel right, mm
  glm::vec4 step_v_mm;     // one pixel down, mm
  glm::ivec4 image;        // (width, height, 0, 0) pixels
};
static_assert(sizeof(SliceVolumePush) == 128);

}  // namespace vpm::gpu

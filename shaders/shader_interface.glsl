// GLSL mirror of server/gpu/shader_interface.h. Keep the two in step.
#ifndef VPM_SHADER_INTERFACE_GLSL
#define VPM_SHADER_INTERFACE_GLSL

#define VPM_MAX_TF_POINTS 32

struct GradientPush {
  ivec4 dims;             // (nx, ny, nz, 0) voxels
  vec4 inv_two_spacing;   // (1/(2 sx), 1/(2 sy), 1/(2 sz), 0) 1/mm
};

struct VoxelMapPush {
  ivec4 dims;  // (nx, ny, nz, 0) voxels
};

struct LatticeCostsPush {
  ivec4 dims;             // (nx, ny, nz, 0) voxels
  ivec4 grid;             // (Gx, Gy, Gz, 0) lattice vertices
  vec4 inv_two_spacing;   // (1/(2 sx), 1/(2 sy), 1/(2 sz), 0) 1/mm
  ivec4 chunk;            // (z0, z1, cz0, cz1): voxel slices and cell layers of this pass
};

// Ray casting (server/raycast).
#define VPM_RENDER_LUT_ENTRIES 1024
#define VPM_PREINTEGRATED_ENTRIES 256
#define VPM_RAYCAST_SHADING 1
#define VPM_RAYCAST_SKIPPING 2
#define VPM_RAYCAST_EARLY_TERMINATION 4
#define VPM_RAYCAST_HAS_MAP 8
#define VPM_RAYCAST_COUNT_SAMPLES 16
#define VPM_RAYCAST_JITTER 64
#define VPM_RAYCAST_BRIGHTEST_FIRST 256
#define VPM_RAYCAST_PEAK_REFINE 512
#define VPM_RAYCAST_LIGHT_BOTH_ENDS 1024
#define VPM_RAYCAST_PARTIAL_END_STEPS 2048
#define VPM_RAYCAST_MAX_CLIP_PLANES 16

struct BrickMinMaxPush {
  ivec4 dims;          // (nx, ny, nz, 0) voxels
  ivec4 bricks;        // (bx, by, bz, 0) bricks
  ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
};

struct BrickOccupancyPush {
  ivec4 dims;        // (nx, ny, nz, 0) voxels
  ivec4 bricks;        // (bx, by, bz, 0) bricks
  ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
  vec4 spacing_mm;   // (sx, sy, sz, 0)
  vec4 lut;          // (value_lo, entries per value unit, entry count, 0)
  ivec4 flags;       // (mode: 0 DVR / 1 MIP, has_map, box bricks along x, along y)
  vec4 map_dims;     // (Mx, My, Mz, 0) backward-map grid points
  ivec4 box_lo;      // (x, y, z, box bricks along z): the bricks the pass updates
};

struct RaycastParams {
  vec4 eye_mm;      // xyz eye (physical mm); w: step_mm
  vec4 forward;     // xyz unit view direction
  vec4 right;       // xyz camera right * tan(fov/2) * width / shorter side
  vec4 up;          // xyz camera up * tan(fov/2) * height / shorter side
  ivec4 dims;       // (nx, ny, nz, mode: 0 DVR / 1 MIP) voxels
  vec4 spacing_mm;  // (sx, sy, sz, 0)
  ivec4 image;      // (width, height, flags, jitter seed) pixels
  ivec4 bricks;     // (bx, by, bz, 0) bricks
  ivec4 brick_voxels;  // (wx, wy, wz, 0) voxels per brick side
  vec4 lut;         // (value_lo, entries per value unit, entry count, 0)
  vec4 window;      // MIP (value of black, 1 / window width, value of white, 0)
  vec4 background;  // rgb in [0, 1]
  vec4 shading;     // (ambient, diffuse, specular, shininess)
  vec4 map_dims;    // (Mx, My, Mz, 0) backward-map grid points
  vec4 gradient;    // (|grad| at which shading is half on, value/mm; 0, 0, 0)
  ivec4 clip;       // (planes used, 0, 0, 0)
  vec4 clip_planes[VPM_RAYCAST_MAX_CLIP_PLANES];  // keep dot(xyz, x) >= w (mm)
};

struct RaycastBandPush {
  ivec4 rows;  // (band b, bands n, threads t, 0): tile rows b, b + n, b + 2n, ...
};

const int kUpscaleBilinear = 0;
const int kUpscaleCatmullRom = 1;
struct UpscalePush {
  ivec4 size;    // (source width, source height, target width, target height)
  ivec4 mode;    // (kUpscaleBilinear or kUpscaleCatmullRom, 0, 0, 0)
};

struct BackwardMapPush {
  ivec4 map_dims;  // (mx, my, mz, pass) grid points
  vec4 step_mm;    // (hx, hy, hz, eps): grid step extent/(M-1) mm; barycentric tolerance
  // (listed tets, moved tets (listed first, cleared), 0, 0)
  uvec4 work;
};

struct BackwardMapWritePush {
  ivec4 map_dims;  // (mx, my, mz, points per values slab) grid points
  vec4 step_mm;    // (hx, hy, hz, 0): grid step extent/(M-1) mm
  ivec4 box_lo;    // (x, y, z, 0) first grid point of the box
  ivec4 box_hi;    // (x, y, z, 0) last grid point of the box (inclusive)
};

struct BackwardMapTetWork {
  ivec4 old_lo;  // (x, y, z, tet index)
  ivec4 old_hi;  // (x, y, z, 0)
  ivec4 new_lo;  // (x, y, z, 0)
  ivec4 new_hi;  // (x, y, z, 0)
};

struct WarpVolumePush {
  ivec4 dims;         // (nx, ny, nz, exact) voxels; exact = 1: one map point per voxel
  vec4 inv_spacing;   // (1/sx, 1/sy, 1/sz, 0) 1/mm
  vec4 spacing_mm;    // (sx, sy, sz, 0) mm
  vec4 extent_mm;     // ((n-1)*s, 0) mm, the image box
  vec4 map_dims;      // (mx, my, mz, 0) backward-map grid points, as floats
};

struct SliceVolumePush {
  ivec4 dims;         // (nx, ny, nz, 0) voxels
  vec4 inv_spacing;   // (1/sx, 1/sy, 1/sz, 0) 1/mm
  vec4 extent_mm;     // ((n-1)*s, 0) mm, the image box
  vec4 map_dims;      // (mx, my, mz, 0) backward-map grid points, as floats
  vec4 origin_mm;     // physical corner of pixel (0, 0), mm
  vec4 step_u_mm;     // one pixel right, mm
  vec4 step_v_mm;     // one pixel down, mm
  ivec4 image;        // (width, height, 0, 0) pixels
};

#endif

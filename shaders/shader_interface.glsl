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
};

struct BackwardMapPush {
  ivec4 map_dims;  // (mx, my, mz, pass) grid points
  vec4 step_mm;    // (hx, hy, hz, eps): grid step extent/(M-1) mm; barycentric tolerance
  uvec4 work;      // (listed tets, 0, 0, 0)
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

#endif

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

#endif

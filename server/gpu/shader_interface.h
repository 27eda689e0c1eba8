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

// lattice_costs.comp: one workgroup per lattice vertex (cell).
struct LatticeCostsPush {
  glm::ivec4 dims;             // (nx, ny, nz, 0) voxels
  glm::ivec4 grid;             // (Gx, Gy, Gz, 0) lattice vertices
  glm::vec4 inv_two_spacing;   // (1/(2 sx), 1/(2 sy), 1/(2 sz), 0) 1/mm
};
static_assert(sizeof(LatticeCostsPush) == 48);

// Uniform block TransferFunctionBlock (std140): control points (value, cost)
// sorted by value in points[i].xy, count in count.x.
inline constexpr int kMaxTfPoints = 32;
struct TransferFunctionBlock {
  glm::vec4 points[kMaxTfPoints];
  glm::ivec4 count;
};
static_assert(sizeof(TransferFunctionBlock) == 528);

// backward_map.comp: rasterizes the backward map tet by tet. pass (in
// map_dims.w): 0 reset every grid point (one invocation per point), 1 clear
// the old coverage of the listed tets, 2 claim (atomicMin of the tet index),
// 3 write the value of the winning tet (one workgroup per listed tet).
struct BackwardMapPush {
  glm::ivec4 map_dims;  // (mx, my, mz, pass) grid points
  glm::vec4 step_mm;    // (hx, hy, hz, eps): grid step extent/(M-1) mm; barycentric tolerance
  glm::uvec4 work;      // (listed tets, 0, 0, 0)
};
static_assert(sizeof(BackwardMapPush) == 48);

// One listed tet of backward_map.comp (std430 storage buffer element): its
// grid-point box from the previous update (cleared in pass 1) and now
// (claimed and written in passes 2, 3); inclusive, empty when lo > hi.
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

}  // namespace vpm::gpu

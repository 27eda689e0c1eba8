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

}  // namespace vpm::gpu

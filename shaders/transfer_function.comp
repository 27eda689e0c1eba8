#version 450
#extension GL_GOOGLE_include_directive : require
// TF(I) for every voxel.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform isamplerBuffer u_volume;
layout(std140, binding = 1) uniform TransferFunctionBlock {
  vec4 points[VPM_MAX_TF_POINTS];
  ivec4 count;
} u_tf;
layout(std430, binding = 2) writeonly buffer Out { float cost[]; };
layout(push_constant) uniform Push { VoxelMapPush pc; };

#include "transfer_function.glsl"
#include "volume_access.glsl"

void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID);
  ivec3 dims = pc.dims.xyz;
  if (any(greaterThanEqual(p, dims))) return;
  uint n = uint(p.x) + uint(dims.x) * (uint(p.y) + uint(dims.y) * uint(p.z));
  cost[n] = transfer_cost(voxel_linear(int(n)));
}

#version 450
#extension GL_GOOGLE_include_directive : require
// |grad I| for every voxel. One invocation per voxel; 64 along x (a multiple
// of lavapipe's SIMD width), rows along y and z.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform isamplerBuffer u_volume;
layout(std430, binding = 1) writeonly buffer Out { float gradient[]; };
layout(push_constant) uniform Push { GradientPush pc; };

#include "volume_access.glsl"

void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID);
  ivec3 dims = pc.dims.xyz;
  if (any(greaterThanEqual(p, dims))) return;
  uint n = uint(p.x) + uint(dims.x) * (uint(p.y) + uint(dims.y) * uint(p.z));
  gradient[n] = gradient_magnitude_at(p, dims, pc.inv_two_spacing.xyz);
}

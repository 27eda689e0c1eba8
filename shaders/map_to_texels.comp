#version 450
#extension GL_GOOGLE_include_directive : require
// Copies the backward map (RGBA32F 3D image) into a buffer read as a uniform
// texel buffer by the ray caster: on lavapipe eight texel-buffer fetches with
// a manual trilinear cost about half a linear 3D-image sample of RGBA32F
// (docs/RENDERING.md). One invocation per grid point, x fastest.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(std430, binding = 1) writeonly buffer Texels { vec4 texels[]; };
layout(push_constant) uniform Push { MapToTexelsPush pc; };

void main() {
  ivec3 m = pc.map_dims.xyz;
  int index = int(gl_GlobalInvocationID.x);
  if (index >= m.x * m.y * m.z) return;
  ivec3 g = ivec3(index % m.x, (index / m.x) % m.y, index / (m.x * m.y));
  texels[index] = texelFetch(u_map, g, 0);
}

#version 450
#extension GL_GOOGLE_include_directive : require
// J(x) = I(X(x)) per voxel, the source read through its uniform texel buffer
// with a manual trilinear interpolation, the same arithmetic as
// SampleTrilinear (server/volume/sample_trilinear.h). One invocation per
// voxel, 64 along x.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(binding = 1) uniform samplerBuffer u_volume;
layout(std430, binding = 2) writeonly buffer Out { float warped[]; };
layout(push_constant) uniform Push { WarpVolumePush pc; };

float source_at(ivec3 p, ivec3 dims) {
  p = min(p, dims - 1);
  return texelFetch(u_volume, p.x + dims.x * (p.y + dims.y * p.z)).r;
}

float sample_source(vec3 index) {
  ivec3 dims = pc.dims.xyz;
  vec3 n1 = vec3(dims - 1);
  // NaN (a non-finite map value) reads voxel 0 like SampleTrilinear.
  index = mix(index, vec3(0.0), isnan(index));
  index = clamp(index, vec3(0.0), n1);
  // The lower corner stays one below the last voxel so that the upper one
  // exists; its weight is then exactly 1 on the far face.
  vec3 base = min(floor(index), max(n1 - 1.0, vec3(0.0)));
  vec3 f = index - base;
  ivec3 i0 = ivec3(base);
  float c00 = mix(source_at(i0, dims), source_at(i0 + ivec3(1, 0, 0), dims), f.x);
  float c10 = mix(source_at(i0 + ivec3(0, 1, 0), dims), source_at(i0 + ivec3(1, 1, 0), dims), f.x);
  float c01 = mix(source_at(i0 + ivec3(0, 0, 1), dims), source_at(i0 + ivec3(1, 0, 1), dims), f.x);
  float c11 = mix(source_at(i0 + ivec3(0, 1, 1), dims), source_at(i0 + ivec3(1, 1, 1), dims), f.x);
  return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

#include "warp_volume.glsl"

void main() { warp_voxel(); }

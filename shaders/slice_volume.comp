#version 450
#extension GL_GOOGLE_include_directive : require
// A slice of the deformed volume J(x) = I(X(x)): one invocation per pixel,
// 8 x 8 per workgroup. Pixel (i, j) samples the physical point origin +
// (i + 0.5) step_u + (j + 0.5) step_v; X(x) from the backward map through
// its sampler (backward_map.glsl), I by the manual trilinear of
// warp_volume_texel.comp; NaN outside the image box (1e-4 mm margin).
// CPU reference: SampleSliceCpu (server/raycast/slice_sampler.h).
#include "shader_interface.glsl"
#include "backward_map.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(binding = 1) uniform samplerBuffer u_volume;
layout(std430, binding = 2) writeonly buffer Out { float values[]; };
layout(push_constant) uniform Push { SliceVolumePush pc; };

float source_at(ivec3 p, ivec3 dims) {
  p = min(p, dims - 1);
  return texelFetch(u_volume, p.x + dims.x * (p.y + dims.y * p.z)).r;
}

// As SampleTrilinear: clamped to [0, n - 1], NaN reads voxel 0.
float sample_source(vec3 index) {
  ivec3 dims = pc.dims.xyz;
  vec3 n1 = vec3(dims - 1);
  index = mix(index, vec3(0.0), isnan(index));
  index = clamp(index, vec3(0.0), n1);
  vec3 base = min(floor(index), max(n1 - 1.0, vec3(0.0)));
  vec3 f = index - base;
  ivec3 i0 = ivec3(base);
  float c00 = mix(source_at(i0, dims), source_at(i0 + ivec3(1, 0, 0), dims), f.x);
  float c10 = mix(source_at(i0 + ivec3(0, 1, 0), dims), source_at(i0 + ivec3(1, 1, 0), dims), f.x);
  float c01 = mix(source_at(i0 + ivec3(0, 0, 1), dims), source_at(i0 + ivec3(1, 0, 1), dims), f.x);
  float c11 = mix(source_at(i0 + ivec3(0, 1, 1), dims), source_at(i0 + ivec3(1, 1, 1), dims), f.x);
  return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

void main() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= pc.image.x || px.y >= pc.image.y) return;
  vec3 x = pc.origin_mm.xyz + (float(px.x) + 0.5) * pc.step_u_mm.xyz +
           (float(px.y) + 0.5) * pc.step_v_mm.xyz;
  vec3 extent = pc.extent_mm.xyz;
  float value = uintBitsToFloat(0x7fc00000u);  // NaN: outside the box
  if (all(greaterThanEqual(x, vec3(-1e-4))) && all(lessThanEqual(x, extent + 1e-4))) {
    vec3 rest = rest_position(u_map, x, extent, pc.map_dims.xyz);
    value = sample_source(rest * pc.inv_spacing.xyz);
  }
  values[px.y * pc.image.x + px.x] = value;
}

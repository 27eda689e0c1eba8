#version 450
#extension GL_GOOGLE_include_directive : require
// A slice of the deformed volume J(x) = I(X(x)): one invocation per pixel,
// 8 x 8 per workgroup. Pixel (i, j) samples the physical point origin +
// (i + 0.5) step_u + (j + 0.5) step_v; X(x) from the backward map through
// its sampler (backward_map.glsl), I by source_texel_trilinear.glsl (as
// warp_volume_texel.comp); NaN outside the image box (1e-4 mm margin).
// CPU reference: SampleSliceCpu (server/raycast/slice_sampler.h).
#include "shader_interface.glsl"
#include "backward_map.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(binding = 1) uniform isamplerBuffer u_volume;
layout(std430, binding = 2) writeonly buffer Out { float values[]; };
layout(push_constant) uniform Push { SliceVolumePush pc; };

#include "source_texel_trilinear.glsl"

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

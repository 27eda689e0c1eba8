// J(x) = I(X(x)) for every voxel x (docs/ALGORITHM.md section 7): the body shared
// by warp_volume.comp (source read through a sampler3D) and
// warp_volume_texel.comp (source read through a uniform texel buffer, manual
// trilinear). The including shader declares u_map, the Out buffer `warped`,
// the push constants `pc` (WarpVolumePush) and
// `float sample_source(vec3 index)`: the source trilinearly interpolated at
// a continuous index, clamped to [0, n - 1] per axis (section 0).
#ifndef VPM_WARP_VOLUME_GLSL
#define VPM_WARP_VOLUME_GLSL

#include "backward_map.glsl"

void warp_voxel() {
  ivec3 v = ivec3(gl_GlobalInvocationID);
  ivec3 dims = pc.dims.xyz;
  if (any(greaterThanEqual(v, dims))) return;
  // With one map point per voxel (the exact mode) the map is read at the
  // voxel itself: no interpolation, no coordinate round-off.
  vec4 m = pc.dims.w != 0 ? texelFetch(u_map, v, 0)
                          : backward_map_sample(u_map, vec3(v) * pc.spacing_mm.xyz,
                                                pc.extent_mm.xyz, pc.map_dims.xyz);
  // The rest position as a continuous index: where the displacement is 0 it
  // is the voxel's own integer index, so identity reads the voxel exactly.
  vec3 rest_index = vec3(v) + m.xyz * pc.inv_spacing.xyz;
  uint n = uint(v.x) + uint(dims.x) * (uint(v.y) + uint(dims.y) * uint(v.z));
  warped[n] = sample_source(rest_index);
}

#endif

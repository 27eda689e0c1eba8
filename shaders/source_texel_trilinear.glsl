// The source volume read from its uniform texel buffer with a manual
// trilinear interpolation, the arithmetic of SampleTrilinear
// (server/volume/sample_trilinear.h): bit-exact at integer indices. Shared
// by warp_volume_texel.comp and slice_volume.comp; the including shader
// declares `uniform isamplerBuffer u_volume` (volume_access.glsl) and push
// constants `pc` whose `dims.xyz` are the volume's voxels.
#ifndef VPM_SOURCE_TEXEL_TRILINEAR_GLSL
#define VPM_SOURCE_TEXEL_TRILINEAR_GLSL

#include "volume_access.glsl"

float source_at(ivec3 p, ivec3 dims) {
  p = min(p, dims - 1);
  return voxel_at(p, dims);
}

// I at a continuous index, clamped to [0, n - 1] per axis (section 0).
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

#endif

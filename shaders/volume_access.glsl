// Voxel reads with the clamped indexing of ALGORITHM.md section 0.
// Expects `uniform sampler3D u_volume` (R32F, one texel per voxel) declared
// by the including shader.
#ifndef VPM_VOLUME_ACCESS_GLSL
#define VPM_VOLUME_ACCESS_GLSL

float voxel_clamped(ivec3 p, ivec3 dims) {
  return texelFetch(u_volume, clamp(p, ivec3(0), dims - 1), 0).r;
}

// |grad I| at voxel p, central differences in value/mm; the same operation
// order as the CPU reference ((a - b) * 1/(2 s)).
float gradient_magnitude_at(ivec3 p, ivec3 dims, vec3 inv_two_spacing) {
  float gx = (voxel_clamped(p + ivec3(1, 0, 0), dims) - voxel_clamped(p - ivec3(1, 0, 0), dims)) *
             inv_two_spacing.x;
  float gy = (voxel_clamped(p + ivec3(0, 1, 0), dims) - voxel_clamped(p - ivec3(0, 1, 0), dims)) *
             inv_two_spacing.y;
  float gz = (voxel_clamped(p + ivec3(0, 0, 1), dims) - voxel_clamped(p - ivec3(0, 0, 1), dims)) *
             inv_two_spacing.z;
  return sqrt(gx * gx + gy * gy + gz * gz);
}

#endif

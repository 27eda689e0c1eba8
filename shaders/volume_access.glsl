// Voxel reads with the clamped indexing of docs/ALGORITHM.md section 0.
// Expects `uniform samplerBuffer u_volume` (R32F, one texel per voxel, x
// fastest) declared by the including shader: on lavapipe a uniform texel
// buffer reads about twice as fast as a 3D image (docs/LAVAPIPE.md).
#ifndef VPM_VOLUME_ACCESS_GLSL
#define VPM_VOLUME_ACCESS_GLSL

float voxel_at(ivec3 p, ivec3 dims) { return texelFetch(u_volume, p.x + dims.x * (p.y + dims.y * p.z)).r; }

float voxel_clamped(ivec3 p, ivec3 dims) { return voxel_at(clamp(p, ivec3(0), dims - 1), dims); }

// |grad I|^2 at voxel p, central differences in (value/mm)^2. The CPU
// reference divides by 2s where this multiplies by 1/(2s): an ulp apart.
float gradient_squared_at(ivec3 p, ivec3 dims, vec3 inv_two_spacing) {
  float gx = (voxel_clamped(p + ivec3(1, 0, 0), dims) - voxel_clamped(p - ivec3(1, 0, 0), dims)) *
             inv_two_spacing.x;
  float gy = (voxel_clamped(p + ivec3(0, 1, 0), dims) - voxel_clamped(p - ivec3(0, 1, 0), dims)) *
             inv_two_spacing.y;
  float gz = (voxel_clamped(p + ivec3(0, 0, 1), dims) - voxel_clamped(p - ivec3(0, 0, 1), dims)) *
             inv_two_spacing.z;
  return gx * gx + gy * gy + gz * gz;
}

float gradient_magnitude_at(ivec3 p, ivec3 dims, vec3 inv_two_spacing) {
  return sqrt(gradient_squared_at(p, dims, inv_two_spacing));
}

#endif

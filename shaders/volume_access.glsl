// Voxel reads with the clamped indexing of docs/ALGORITHM.md section 0.
// Expects `uniform isamplerBuffer u_volume` declared by the including shader:
// the volume as GpuVolume holds it (server/volume/gpu_volume.h), x fastest,
// in pairs (texel n holds voxels n and n + 1) or, for int16 volumes over the
// texel-buffer limit, packed (2 voxels per texel); voxel_encoding.glsl
// decodes both. A uniform texel buffer reads about twice as fast as a 3D
// image or a storage buffer on lavapipe (docs/LAVAPIPE.md).
#ifndef VPM_VOLUME_ACCESS_GLSL
#define VPM_VOLUME_ACCESS_GLSL

#include "voxel_encoding.glsl"

// Voxel n (linear index, x fastest) as a float: exact, the value
// VoxelValues::operator[] returns on the CPU.
float voxel_linear(int n) { return VPM_DECODE_TEXEL_VOXEL(u_volume, n); }

// Voxels n and n + 1 (x fastest: n's neighbour along x when x < dims.x - 1).
vec2 voxel_pair(int n) { return VPM_DECODE_TEXEL_PAIR(u_volume, n); }

float voxel_at(ivec3 p, ivec3 dims) { return voxel_linear(p.x + dims.x * (p.y + dims.y * p.z)); }

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

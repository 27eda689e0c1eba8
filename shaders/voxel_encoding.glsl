// How a volume's voxels are held (server/volume/voxel_values.h) and laid out
// in its texel buffer (server/volume/gpu_volume.h), as specialization
// constants 1, 2 and 4 of every kernel that reads a volume
// (GpuVolume::Specialize sets them; constants 0 and 3 stay the kernel's own).
#ifndef VPM_VOXEL_ENCODING_GLSL
#define VPM_VOXEL_ENCODING_GLSL

// true: int16 voxels, value = stored + kVoxelOffset; false: float bits.
layout(constant_id = 1) const bool kVoxelsInt16 = false;
layout(constant_id = 2) const int kVoxelOffset = 0;
// true: texel n holds voxels n and n + 1 (int16: low and high halves of its
// R32_SINT; float: the bits of both in its R32G32_SINT); false: int16
// packed, texel t holds voxels 2t and 2t + 1.
layout(constant_id = 4) const bool kVoxelsPaired = false;

// Voxel n of the volume's texel buffer u_volume as a float: int16 values as
// an integer add and an exact conversion (|value| <= 2^24), floats from
// their bits. One 32-bit channel per fetch where the layout allows: lavapipe
// converts every channel of a texel it fetches, so RGBA texels of 4 voxels
// cost 40% more in step 1 (measured).
#define VPM_INT16_VOXEL(texel, bit) float(bitfieldExtract(texel, bit, 16) + kVoxelOffset)
#define VPM_DECODE_TEXEL_VOXEL(tex, n)                                      \
  (kVoxelsPaired ? (kVoxelsInt16 ? VPM_INT16_VOXEL(texelFetch(tex, (n)).r, 0) \
                                 : intBitsToFloat(texelFetch(tex, (n)).r))  \
                 : VPM_INT16_VOXEL(texelFetch(tex, (n) >> 1).r, ((n) & 1) << 4))

// Voxels n and n + 1 (the next along x): one fetch where paired, else two.
#define VPM_DECODE_TEXEL_PAIR(tex, n) \
  (kVoxelsPaired ? decode_pair_texel(texelFetch(tex, (n)).rg) \
                 : vec2(VPM_DECODE_TEXEL_VOXEL(tex, n), VPM_DECODE_TEXEL_VOXEL(tex, (n) + 1)))

// A paired texel's two voxels (its .rg: int16 in r's halves, or floats' bits).
vec2 decode_pair_texel(ivec2 t) {
  return kVoxelsInt16 ? vec2(VPM_INT16_VOXEL(t.r, 0), VPM_INT16_VOXEL(t.r, 16))
                      : intBitsToFloat(t);
}

// A channel of the volume's 3D image (GpuVolume::Image): R16_UNORM holding
// stored + 32768 for int16 volumes (within 65535 * 2^-24 of the value), R32F
// for float volumes.
float decode_image_voxel(float v) {
  return kVoxelsInt16 ? v * 65535.0 + float(kVoxelOffset - 32768) : v;
}

#endif

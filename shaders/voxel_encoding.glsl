// How a volume's voxels are held (server/volume/voxel_values.h), as
// specialization constants 1 and 2 of every kernel that reads a volume
// (GpuVolume::Specialize sets them; constant 0 stays each kernel's own).
#ifndef VPM_VOXEL_ENCODING_GLSL
#define VPM_VOXEL_ENCODING_GLSL

// true: int16 voxels, value = stored + kVoxelOffset; false: float bits.
layout(constant_id = 1) const bool kVoxelsInt16 = false;
layout(constant_id = 2) const int kVoxelOffset = 0;

// Voxel n of the volume's R32_SINT texel buffer u_volume as a float: int16
// volumes hold 2 voxels per texel (voxel 2t in the low half of texel t), read
// as an integer add and an exact conversion (|value| <= 2^24); float volumes
// hold one per texel, its bits. One 32-bit channel per fetch: lavapipe
// converts every channel of a texel it fetches, so RGBA texels of 4 voxels
// cost 40% more in step 1 (measured).
#define VPM_DECODE_TEXEL_VOXEL(tex, n)                                                   \
  (kVoxelsInt16 ? float(bitfieldExtract(texelFetch(tex, (n) >> 1).r, ((n) & 1) << 4, 16) + \
                        kVoxelOffset)                                                  \
                : intBitsToFloat(texelFetch(tex, (n)).r))

// A channel of the volume's 3D image (GpuVolume::Image): R16_UNORM holding
// stored + 32768 for int16 volumes (within 65535 * 2^-24 of the value), R32F
// for float volumes.
float decode_image_voxel(float v) {
  return kVoxelsInt16 ? v * 65535.0 + float(kVoxelOffset - 32768) : v;
}

#endif

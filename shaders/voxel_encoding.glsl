// How a volume's voxels are held (server/volume/voxel_values.h), as
// specialization constants 1 and 2 of every kernel that reads a volume
// (GpuVolume::Specialize sets them; constant 0 stays each kernel's own).
#ifndef VPM_VOXEL_ENCODING_GLSL
#define VPM_VOXEL_ENCODING_GLSL

// true: int16 voxels, value = stored + kVoxelOffset; false: float bits.
layout(constant_id = 1) const bool kVoxelsInt16 = false;
layout(constant_id = 2) const int kVoxelOffset = 0;

// A texel-buffer channel as a float: an integer add and an exact conversion
// (|value| <= 2^24), or the float's own bits.
float decode_voxel(int raw) { return kVoxelsInt16 ? float(raw + kVoxelOffset) : intBitsToFloat(raw); }

// A channel of the volume's 3D image (GpuVolume::Image): R16_UNORM holding
// stored + 32768 for int16 volumes (within 65535 * 2^-24 of the value), R32F
// for float volumes.
float decode_image_voxel(float v) {
  return kVoxelsInt16 ? v * 65535.0 + float(kVoxelOffset - 32768) : v;
}

#endif

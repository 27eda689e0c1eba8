// The voxel values of a volume as held in memory: 16-bit integers plus an
// exact integer offset (value = stored + offset) for integer sources (CT in
// HU, 8- and 16-bit MRI), 32-bit floats for float sources and for values
// that are not integers or span more than 16 bits. An int16 voxel reads as
// float(int32(stored) + offset): an integer add, then a conversion that is
// exact because |value| <= 2^24, so the CPU, the GPU (shaders/volume_access.glsl)
// and every consumer see the very float a float volume of the same values
// would hold; int16 storage changes no result, only the memory (2 bytes per
// voxel instead of 4).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "server/common/status.h"

namespace vpm {

// The values match the specialization constant kVoxelsInt16 of the shaders
// (0: float, 1: int16).
enum class VoxelEncoding : uint32_t { kFloat32 = 0, kInt16 = 1 };

// "int16" or "float32".
const char* VoxelEncodingName(VoxelEncoding encoding);

// Bytes per voxel in memory, host and device: 2 or 4.
inline int64_t VoxelEncodingBytes(VoxelEncoding encoding) {
  return encoding == VoxelEncoding::kInt16 ? 2 : 4;
}

// Read access to int16 voxels (no bounds checks): value = stored + offset.
struct Int16Voxels {
  const int16_t* stored;
  int32_t offset;
  float operator[](int64_t n) const { return static_cast<float>(int32_t{stored[n]} + offset); }
};

// Read access to float voxels (no bounds checks).
struct FloatVoxels {
  const float* values;
  float operator[](int64_t n) const { return values[n]; }
};

// The largest |value| an int16 volume may hold: every integer up to 2^24 is
// exact in float.
inline constexpr int64_t kMaxExactInt16Value = int64_t{1} << 24;

// The offset that makes integer values in [lo, hi] fit int16 exactly: 0 when
// they already fit, else lo + 32768; nullopt when hi - lo > 65535 or a value
// is past +-kMaxExactInt16Value (then they stay float).
std::optional<int32_t> Int16OffsetFor(int64_t lo, int64_t hi);

class VoxelValues {
 public:
  VoxelValues() = default;  // no voxels, float
  static VoxelValues Float(std::vector<float> values);
  // `stored` + `offset` per voxel; InvalidArgument when some stored + offset
  // is past +-kMaxExactInt16Value.
  static Result<VoxelValues> Int16(std::vector<int16_t> stored, int32_t offset);

  VoxelEncoding encoding() const { return encoding_; }
  bool is_int16() const { return encoding_ == VoxelEncoding::kInt16; }
  int64_t size() const;
  int64_t bytes_per_voxel() const { return VoxelEncodingBytes(encoding_); }
  // The integer offset of int16 values (0 for floats).
  int32_t int16_offset() const { return offset_; }

  // Value n (no bounds check); branches on the encoding: hot loops use Visit.
  float operator[](int64_t n) const {
    return is_int16() ? static_cast<float>(int32_t{int16_[n]} + offset_) : float_[n];
  }
  // Calls f(Int16Voxels) or f(FloatVoxels), so that a loop templated on the
  // accessor compiles once per encoding without a branch per voxel.
  template <typename F>
  decltype(auto) Visit(F&& f) const {
    if (is_int16()) return f(Int16Voxels{int16_.data(), offset_});
    return f(FloatVoxels{float_.data()});
  }

  // The stored bytes (int16 or float, x fastest), for uploads and writers.
  std::span<const std::byte> bytes() const;
  std::span<const float> floats() const { return float_; }       // empty unless float
  std::span<const int16_t> int16s() const { return int16_; }     // empty unless int16
  std::span<float> mutable_floats() { return float_; }           // empty unless float
  // Every value as a float (a copy: 4 bytes per voxel; tests, small volumes).
  std::vector<float> ToFloats() const;

 private:
  VoxelEncoding encoding_ = VoxelEncoding::kFloat32;
  std::vector<float> float_;
  std::vector<int16_t> int16_;
  int32_t offset_ = 0;
};

}  // namespace vpm

#include "server/volume/voxel_values.h"

#include <algorithm>

namespace vpm {

const char* VoxelEncodingName(VoxelEncoding encoding) {
  return encoding == VoxelEncoding::kInt16 ? "int16" : "float32";
}

std::optional<int32_t> Int16OffsetFor(int64_t lo, int64_t hi) {
  if (lo > hi || hi - lo > 65535) return std::nullopt;
  if (lo < -kMaxExactInt16Value || hi > kMaxExactInt16Value) return std::nullopt;
  if (lo >= -32768 && hi <= 32767) return 0;
  return static_cast<int32_t>(lo + 32768);
}

VoxelValues VoxelValues::Float(std::vector<float> values) {
  VoxelValues v;
  v.encoding_ = VoxelEncoding::kFloat32;
  v.float_ = std::move(values);
  return v;
}

Result<VoxelValues> VoxelValues::Int16(std::vector<int16_t> stored, int32_t offset) {
  if (int64_t{offset} - 32768 < -kMaxExactInt16Value ||
      int64_t{offset} + 32767 > kMaxExactInt16Value) {
    // Only the values actually held need to be exact.
    const auto [lo, hi] = std::minmax_element(stored.begin(), stored.end());
    if (lo != stored.end() && (int64_t{*lo} + offset < -kMaxExactInt16Value ||
                               int64_t{*hi} + offset > kMaxExactInt16Value)) {
      return absl::InvalidArgumentError(
          StrCat("int16 voxels with offset ", offset, " reach past +-", kMaxExactInt16Value,
                 ", where float is no longer exact"));
    }
  }
  VoxelValues v;
  v.encoding_ = VoxelEncoding::kInt16;
  v.int16_ = std::move(stored);
  v.offset_ = offset;
  return v;
}

int64_t VoxelValues::size() const {
  return static_cast<int64_t>(is_int16() ? int16_.size() : float_.size());
}

std::span<const std::byte> VoxelValues::bytes() const {
  return is_int16() ? std::as_bytes(std::span<const int16_t>(int16_))
                    : std::as_bytes(std::span<const float>(float_));
}

std::vector<float> VoxelValues::ToFloats() const {
  std::vector<float> out(static_cast<size_t>(size()));
  Visit([&](const auto& voxels) {
    for (size_t n = 0; n < out.size(); ++n) out[n] = voxels[static_cast<int64_t>(n)];
  });
  return out;
}

}  // namespace vpm

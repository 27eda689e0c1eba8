// Scalar voxel types as files store them, and their conversion to float.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"
#include "server/io/byte_order.h"

namespace vpm {

enum class VoxelType {
  kUint8,
  kInt8,
  kUint16,
  kInt16,
  kUint32,
  kInt32,
  kUint64,
  kInt64,
  kFloat32,
  kFloat64
};

// Bytes per voxel: 1, 2, 4 or 8.
int64_t VoxelTypeSize(VoxelType type);
// Canonical lower-case name: "uint8", "int16", "float32", "float64", ...
const char* VoxelTypeName(VoxelType type);
// Inverse of VoxelTypeName; also accepts "float" and "double".
std::optional<VoxelType> VoxelTypeFromName(std::string_view name);

// "256x256x200 int16 (26214400 bytes of data)", for messages. Assumes dims
// already passed ValidateGeometry (no overflow).
std::string DescribeVoxelData(const std::array<int64_t, 3>& dims, VoxelType type);

// double -> float that saturates to +-infinity outside float's range (a
// plain cast is undefined behaviour there); NaN stays NaN.
float DoubleToFloat(double value);

// Converts `count` voxels stored back to back in `bytes` (type `type`, byte
// order `endian`) to float, in storage order. Each value becomes
// float(value * slope + intercept), computed in double. Fails when `bytes`
// holds fewer than count * VoxelTypeSize(type) bytes; extra bytes are ignored.
Result<std::vector<float>> ConvertVoxelsToFloat(std::span<const uint8_t> bytes, VoxelType type,
                                                Endian endian, int64_t count, double slope = 1.0,
                                                double intercept = 0.0);

}  // namespace vpm

#include "server/io/voxel_type.h"

#include <limits>

namespace vpm {
namespace {

struct TypeInfo {
  VoxelType type;
  std::string_view name;
  int64_t size;
};

constexpr std::array<TypeInfo, 10> kTypes = {{
    {VoxelType::kUint8, "uint8", 1},
    {VoxelType::kInt8, "int8", 1},
    {VoxelType::kUint16, "uint16", 2},
    {VoxelType::kInt16, "int16", 2},
    {VoxelType::kUint32, "uint32", 4},
    {VoxelType::kInt32, "int32", 4},
    {VoxelType::kUint64, "uint64", 8},
    {VoxelType::kInt64, "int64", 8},
    {VoxelType::kFloat32, "float32", 4},
    {VoxelType::kFloat64, "float64", 8},
}};

const TypeInfo& Info(VoxelType type) {
  for (const TypeInfo& info : kTypes) {
    if (info.type == type) return info;
  }
  return kTypes[0];  // unreachable: every enumerator is in the table
}

template <typename T>
void Convert(const uint8_t* bytes, Endian endian, int64_t count, double slope, double intercept,
             float* out) {
  const bool identity = slope == 1.0 && intercept == 0.0;
  for (int64_t n = 0; n < count; ++n) {
    const T raw = LoadScalar<T>(bytes + n * int64_t{sizeof(T)}, endian);
    const double value = static_cast<double>(raw);
    out[n] = DoubleToFloat(identity ? value : value * slope + intercept);
  }
}

}  // namespace

// Values outside float's range become +-infinity, which Volume::Create then
// counts and replaces like NaN.
float DoubleToFloat(double value) {
  if (value > std::numeric_limits<float>::max()) return std::numeric_limits<float>::infinity();
  if (value < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::infinity();
  return static_cast<float>(value);
}

int64_t VoxelTypeSize(VoxelType type) { return Info(type).size; }

const char* VoxelTypeName(VoxelType type) { return Info(type).name.data(); }

std::optional<VoxelType> VoxelTypeFromName(std::string_view name) {
  if (name == "float") return VoxelType::kFloat32;
  if (name == "double") return VoxelType::kFloat64;
  for (const TypeInfo& info : kTypes) {
    if (info.name == name) return info.type;
  }
  return std::nullopt;
}

std::string DescribeVoxelData(const std::array<int64_t, 3>& dims, VoxelType type) {
  const int64_t bytes = dims[0] * dims[1] * dims[2] * VoxelTypeSize(type);
  return StrCat(dims[0], "x", dims[1], "x", dims[2], " ", VoxelTypeName(type), " (", bytes,
                      " bytes of data)");
}

Result<std::vector<float>> ConvertVoxelsToFloat(std::span<const uint8_t> bytes, VoxelType type,
                                                Endian endian, int64_t count, double slope,
                                                double intercept) {
  const int64_t size = VoxelTypeSize(type);
  if (count < 0 || count > static_cast<int64_t>(bytes.size()) / size) {
    return absl::InvalidArgumentError(StrCat("need ", count, " ", VoxelTypeName(type),
                                                   " voxels but only ", bytes.size(),
                                                   " bytes are there"));
  }
  std::vector<float> out(static_cast<size_t>(count));
  const uint8_t* p = bytes.data();
  float* o = out.data();
  switch (type) {
    case VoxelType::kUint8:
      Convert<uint8_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kInt8:
      Convert<int8_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kUint16:
      Convert<uint16_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kInt16:
      Convert<int16_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kUint32:
      Convert<uint32_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kInt32:
      Convert<int32_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kUint64:
      Convert<uint64_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kInt64:
      Convert<int64_t>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kFloat32:
      Convert<float>(p, endian, count, slope, intercept, o);
      break;
    case VoxelType::kFloat64:
      Convert<double>(p, endian, count, slope, intercept, o);
      break;
  }
  return out;
}

}  // namespace vpm

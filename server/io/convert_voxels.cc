#include "server/io/convert_voxels.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "server/common/huge_pages.h"

namespace vpm {
namespace {

// Voxels converted between two polls of the load's CancelToken (1-3 ms).
constexpr int64_t kSlabVoxels = int64_t{1} << 20;

// The integer range of the values, or why they are not int16 material.
struct IntegerRange {
  bool integers = true;
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
};

template <typename T>
IntegerRange ScanRange(const uint8_t* bytes, Endian endian, int64_t count, double slope,
                       double intercept) {
  IntegerRange r;
  const bool identity = slope == 1.0 && intercept == 0.0;
  for (int64_t n = 0; n < count; ++n) {
    const double raw = static_cast<double>(LoadScalar<T>(bytes + n * int64_t{sizeof(T)}, endian));
    const double v = identity ? raw : raw * slope + intercept;
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
    if (!identity && v != std::floor(v)) {
      r.integers = false;
      break;
    }
  }
  return r;
}

template <typename T>
void ToInt16(const uint8_t* bytes, Endian endian, int64_t count, double slope, double intercept,
             int32_t offset, int16_t* out) {
  const bool identity = slope == 1.0 && intercept == 0.0;
  for (int64_t n = 0; n < count; ++n) {
    const T raw = LoadScalar<T>(bytes + n * int64_t{sizeof(T)}, endian);
    const int64_t v = identity ? static_cast<int64_t>(raw)
                               : static_cast<int64_t>(static_cast<double>(raw) * slope + intercept);
    out[n] = static_cast<int16_t>(v - offset);
  }
}

// Calls f.template operator()<T>() with T the C++ type of an integer `type`.
template <typename F>
void WithIntegerType(VoxelType type, F&& f) {
  switch (type) {
    case VoxelType::kUint8: f(uint8_t{}); break;
    case VoxelType::kInt8: f(int8_t{}); break;
    case VoxelType::kUint16: f(uint16_t{}); break;
    case VoxelType::kInt16: f(int16_t{}); break;
    case VoxelType::kUint32: f(uint32_t{}); break;
    case VoxelType::kInt32: f(int32_t{}); break;
    case VoxelType::kUint64: f(uint64_t{}); break;
    case VoxelType::kInt64: f(int64_t{}); break;
    default: break;
  }
}

bool IsIntegerType(VoxelType type) {
  return type != VoxelType::kFloat32 && type != VoxelType::kFloat64;
}

// The int16 offset for values in `r`, if they are int16 material.
std::optional<int32_t> ExactOffset(const IntegerRange& r) {
  if (!r.integers || !(std::abs(r.lo) <= double(kMaxExactInt16Value)) ||
      !(std::abs(r.hi) <= double(kMaxExactInt16Value))) {
    return std::nullopt;
  }
  return Int16OffsetFor(static_cast<int64_t>(r.lo), static_cast<int64_t>(r.hi));
}

std::string WhyFloat(const IntegerRange& r) {
  if (!r.integers) return "stored as float32: the rescaled values are not integers";
  return StrCat("stored as float32: values ", r.lo, " to ", r.hi,
                " do not fit 16 bits with an exact offset");
}

// The rescaled values' range over `count` integer voxels, in slabs of
// kSlabVoxels, polling `cancel` between them; stops at the first slab with a
// value that is not an integer.
Result<IntegerRange> ScanIntegerRange(std::span<const uint8_t> bytes, VoxelType type, Endian endian,
                                      int64_t count, double slope, double intercept,
                                      const CancelToken& cancel) {
  const int64_t size = VoxelTypeSize(type);
  IntegerRange range;
  for (int64_t first = 0; first < count && range.integers; first += kSlabVoxels) {
    RETURN_IF_ERROR(cancel.Check());
    const int64_t n = std::min(kSlabVoxels, count - first);
    WithIntegerType(type, [&](auto tag) {
      const IntegerRange slab =
          ScanRange<decltype(tag)>(bytes.data() + first * size, endian, n, slope, intercept);
      range = {range.integers && slab.integers, std::min(range.lo, slab.lo),
               std::max(range.hi, slab.hi)};
    });
  }
  return range;
}

}  // namespace

bool StoredAsInt16AsIs(VoxelType type, Endian endian, double slope, double intercept) {
  return type == VoxelType::kInt16 && endian == HostEndian() && slope == 1.0 &&
         intercept == std::floor(intercept) && std::abs(intercept) <= 32768.0;
}

Result<VoxelValues> ConvertVoxels(std::span<const uint8_t> bytes, VoxelType type, Endian endian,
                                  const VolumeGeometry& geometry, const VolumeLimits& limits,
                                  double slope, double intercept, std::string* float_note) {
  const int64_t count = geometry.voxel_count();
  const int64_t size = VoxelTypeSize(type);
  if (count < 0 || count > static_cast<int64_t>(bytes.size()) / size) {
    return absl::InvalidArgumentError(StrCat("need ", count, " ", VoxelTypeName(type),
                                             " voxels but only ", bytes.size(),
                                             " bytes are there"));
  }
  // The common CT file: int16 in the machine's byte order, no rescale (or
  // an integer one that keeps the range): the stored bytes as they are.
  if (StoredAsInt16AsIs(type, endian, slope, intercept)) {
    RETURN_IF_ERROR(ValidateGeometry(geometry, limits, VoxelEncoding::kInt16));
    std::vector<int16_t> stored = HugePageVector<int16_t>(static_cast<size_t>(count));
    std::memcpy(stored.data(), bytes.data(), stored.size() * sizeof(int16_t));
    return VoxelValues::Int16(std::move(stored), static_cast<int32_t>(intercept));
  }
  if (IsIntegerType(type) && std::isfinite(slope) && std::isfinite(intercept)) {
    ASSIGN_OR_RETURN(const IntegerRange range,
                     ScanIntegerRange(bytes, type, endian, count, slope, intercept, limits.cancel));
    const std::optional<int32_t> offset = ExactOffset(range);
    if (offset) {
      RETURN_IF_ERROR(ValidateGeometry(geometry, limits, VoxelEncoding::kInt16));
      // Grown a slab at a time within its reservation: no zero-fill of the
      // whole volume between two polls.
      std::vector<int16_t> stored;
      stored.reserve(static_cast<size_t>(count));
      for (int64_t first = 0; first < count; first += kSlabVoxels) {
        RETURN_IF_ERROR(limits.cancel.Check());
        const int64_t n = std::min(kSlabVoxels, count - first);
        stored.resize(static_cast<size_t>(first + n));
        WithIntegerType(type, [&](auto tag) {
          ToInt16<decltype(tag)>(bytes.data() + first * size, endian, n, slope, intercept, *offset,
                                 stored.data() + first);
        });
      }
      return VoxelValues::Int16(std::move(stored), *offset);
    }
    if (float_note != nullptr) *float_note = WhyFloat(range);
  }
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits, VoxelEncoding::kFloat32));
  std::vector<float> values;
  values.reserve(static_cast<size_t>(count));
  AdviseHugePages(values.data(), static_cast<size_t>(count) * sizeof(float));
  for (int64_t first = 0; first < count; first += kSlabVoxels) {
    RETURN_IF_ERROR(limits.cancel.Check());
    const int64_t n = std::min(kSlabVoxels, count - first);
    ASSIGN_OR_RETURN(const std::vector<float> slab,
                     ConvertVoxelsToFloat(bytes.subspan(static_cast<size_t>(first * size)), type,
                                          endian, n, slope, intercept));
    values.insert(values.end(), slab.begin(), slab.end());
  }
  return VoxelValues::Float(std::move(values));
}

Result<Volume> VolumeFromStoredVoxels(std::span<const uint8_t> bytes, VoxelType type,
                                      Endian endian, const VolumeGeometry& geometry,
                                      const VolumeLimits& limits, std::string_view name,
                                      double slope, double intercept) {
  std::string note;
  ASSIGN_OR_RETURN(VoxelValues values, ConvertVoxels(bytes, type, endian, geometry, limits, slope,
                                                     intercept, &note));
  RETURN_IF_ERROR(limits.cancel.Check());
  ASSIGN_OR_RETURN(Volume volume, Volume::Create(geometry, std::move(values), limits));
  volume.set_source(std::string(name));
  if (!note.empty()) volume.add_note(std::move(note));
  return volume;
}

std::optional<int32_t> IntegerRangeOfFloats::Offset() const {
  return ExactOffset(IntegerRange{integers_, lo_, hi_});
}

std::string IntegerRangeOfFloats::WhyFloat() const {
  return vpm::WhyFloat(IntegerRange{integers_, lo_, hi_});
}

Result<VoxelValues> FloatsToVoxels(std::vector<float> values, const VolumeGeometry& geometry,
                                   const VolumeLimits& limits, std::string* float_note) {
  IntegerRangeOfFloats range;
  for (size_t n = 0; n < values.size(); ++n) {
    if (n % static_cast<size_t>(kSlabVoxels) == 0) RETURN_IF_ERROR(limits.cancel.Check());
    range.Add(values[n]);
  }
  const std::optional<int32_t> offset = range.Offset();
  if (!offset) {
    if (float_note != nullptr) *float_note = range.WhyFloat();
    RETURN_IF_ERROR(ValidateGeometry(geometry, limits, VoxelEncoding::kFloat32));
    return VoxelValues::Float(std::move(values));
  }
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits, VoxelEncoding::kInt16));
  std::vector<int16_t> stored = HugePageVector<int16_t>(values.size());
  for (size_t n = 0; n < values.size(); ++n) {
    stored[n] = static_cast<int16_t>(static_cast<int32_t>(values[n]) - *offset);
  }
  values = {};
  return VoxelValues::Int16(std::move(stored), *offset);
}

}  // namespace vpm

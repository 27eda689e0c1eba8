#include "server/io/read_raw.h"

#include <string>
#include <vector>

#include "server/common/prefix_status.h"
#include "server/io/convert_voxels.h"
#include "server/io/read_file_bytes.h"

namespace vpm {
namespace {

Result<Volume> DecodeRaw(std::span<const uint8_t> bytes, std::string_view name,
                         const RawOptions& options, const VolumeLimits& limits) {
  VolumeGeometry geometry;
  geometry.dims = options.dims;
  geometry.spacing_mm = options.spacing_mm;
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits));
  if (options.header_offset_bytes < 0) {
    return absl::InvalidArgumentError(
        StrCat("header offset is ", options.header_offset_bytes, "; it must be >= 0"));
  }
  const int64_t data_bytes = geometry.voxel_count() * VoxelTypeSize(options.type);
  const std::string described =
      StrCat("expected ", DescribeVoxelData(geometry.dims, options.type), " after ",
                   options.header_offset_bytes, " header bytes");
  if (data_bytes > limits.max_bytes ||
      options.header_offset_bytes > limits.max_bytes - data_bytes) {
    return absl::ResourceExhaustedError(
        StrCat(described, ", over the cap of ", limits.max_bytes, " bytes"));
  }
  const int64_t expected = options.header_offset_bytes + data_bytes;
  const int64_t size = static_cast<int64_t>(bytes.size());
  if (size < expected) {
    return absl::InvalidArgumentError(
        StrCat(described, " but the file holds ", size, " bytes (truncated)"));
  }
  if (size > expected) {
    return absl::InvalidArgumentError(StrCat(described, " but the file holds ", size,
                                                   " bytes, ", size - expected,
                                                   " more (wrong dims, type or offset?)"));
  }
  return VolumeFromStoredVoxels(bytes.subspan(static_cast<size_t>(options.header_offset_bytes)),
                                options.type, options.endian, geometry, limits, name);
}

}  // namespace

Result<Volume> ReadRawFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                 const RawOptions& options, const VolumeLimits& limits) {
  Result<Volume> volume = DecodeRaw(bytes, name, options, limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), name);
  return volume;
}

Result<Volume> ReadRaw(const std::filesystem::path& path, const RawOptions& options,
                       const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path, limits));
  return ReadRawFromMemory(bytes, path.string(), options, limits);
}

}  // namespace vpm

#include "server/io/read_nifti.h"

#include <string>
#include <vector>

#include "server/io/gzip_stream.h"
#include "server/io/nifti_geometry.h"
#include "server/io/nifti_header.h"
#include "server/common/prefix_status.h"
#include "server/io/read_file_bytes.h"
#include "server/io/convert_voxels.h"
#include "server/io/voxel_type.h"

namespace vpm {
namespace {

Result<Volume> DecodeNifti(std::span<const uint8_t> bytes, std::string_view name,
                           const VolumeLimits& limits) {
  const bool gzipped = LooksLikeGzip(bytes);
  std::vector<uint8_t> inflated;
  if (gzipped) {
    ASSIGN_OR_RETURN(inflated, InflatePrefix(bytes, kNifti2HeaderBytes));
  }
  ASSIGN_OR_RETURN(const NiftiHeader header,
                   ParseNiftiHeader(gzipped ? std::span<const uint8_t>(inflated) : bytes));
  ASSIGN_OR_RETURN(const VolumeGeometry geometry, NiftiHeaderGeometry(header));
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits));
  const int64_t voxels = geometry.voxel_count();
  const int64_t data_bytes = voxels * VoxelTypeSize(header.voxel_type);
  const std::string described =
      StrCat("header says ", DescribeVoxelData(geometry.dims, header.voxel_type),
                   " at offset ", header.vox_offset);
  if (data_bytes > limits.max_bytes || header.vox_offset > limits.max_bytes - data_bytes) {
    return absl::ResourceExhaustedError(
        StrCat(described, ", over the cap of ", limits.max_bytes, " bytes"));
  }
  const int64_t needed = header.vox_offset + data_bytes;
  if (gzipped) {
    Result<std::vector<uint8_t>> all = InflateExactly(bytes, needed, limits);
    if (!all.ok()) return PrefixStatus(all.status(), described);
    inflated = std::move(*all);
    bytes = inflated;
  } else if (static_cast<int64_t>(bytes.size()) < needed) {
    return absl::InvalidArgumentError(
        StrCat(described, " but the file holds ", bytes.size(), " bytes (truncated)"));
  }
  const auto [slope, intercept] = NiftiScaling(header);
  return VolumeFromStoredVoxels(bytes.subspan(static_cast<size_t>(header.vox_offset)),
                                header.voxel_type, header.endian, geometry, limits, name, slope,
                                intercept);
}

}  // namespace

Result<Volume> ReadNiftiFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                   const VolumeLimits& limits) {
  Result<Volume> volume = DecodeNifti(bytes, name, limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), name);
  return volume;
}

Result<Volume> ReadNifti(const std::filesystem::path& path, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path, limits));
  return ReadNiftiFromMemory(bytes, path.string(), limits);
}

}  // namespace vpm

#include "server/io/read_nifti.h"

#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "server/common/huge_pages.h"
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

// An uncompressed file of int16 voxels as the machine stores them (the
// usual CT): the voxels read straight into the volume's storage, without the
// whole file in memory first and a copy (on a 512 x 512 x 900 CT: 450 MiB
// less at the peak, and a copy of as much saved). nullopt for any other
// file, and for one whose header or size is wrong: DecodeNifti then reads
// it and reports what is wrong.
Result<std::optional<Volume>> ReadInt16NiftiInPlace(const std::filesystem::path& path,
                                                    const VolumeLimits& limits) {
  const Result<std::vector<uint8_t>> prefix = ReadFilePrefix(path, kNifti2HeaderBytes, limits);
  if (!prefix.ok() || LooksLikeGzip(*prefix)) return std::nullopt;
  const Result<NiftiHeader> header = ParseNiftiHeader(*prefix);
  if (!header.ok()) return std::nullopt;
  const auto [slope, intercept] = NiftiScaling(*header);
  if (!StoredAsInt16AsIs(header->voxel_type, header->endian, slope, intercept)) {
    return std::nullopt;
  }
  const Result<VolumeGeometry> geometry = NiftiHeaderGeometry(*header);
  if (!geometry.ok() || !ValidateGeometry(*geometry, limits, VoxelEncoding::kInt16).ok()) {
    return std::nullopt;
  }
  const int64_t data_bytes = geometry->voxel_count() * int64_t{sizeof(int16_t)};
  std::error_code ec;
  const uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec || file_size > uintmax_t(limits.max_bytes) || header->vox_offset < 0 ||
      uintmax_t(header->vox_offset) + uintmax_t(data_bytes) > file_size) {
    return std::nullopt;
  }
  std::vector<int16_t> stored = HugePageVector<int16_t>(size_t(geometry->voxel_count()));
  RETURN_IF_ERROR(ReadFileRangeInto(
      path, header->vox_offset,
      std::span<uint8_t>(reinterpret_cast<uint8_t*>(stored.data()), size_t(data_bytes)), limits));
  Result<VoxelValues> values =
      VoxelValues::Int16(std::move(stored), static_cast<int32_t>(intercept));
  if (!values.ok()) return PrefixStatus(values.status(), path.string());
  Result<Volume> volume = Volume::Create(*geometry, std::move(*values), limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), path.string());
  volume->set_source(path.string());
  return std::optional<Volume>(std::move(*volume));
}

}  // namespace

Result<Volume> ReadNiftiFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                   const VolumeLimits& limits) {
  Result<Volume> volume = DecodeNifti(bytes, name, limits);
  if (!volume.ok()) return PrefixStatus(volume.status(), name);
  return volume;
}

Result<Volume> ReadNifti(const std::filesystem::path& path, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(std::optional<Volume> in_place, ReadInt16NiftiInPlace(path, limits));
  if (in_place) return std::move(*in_place);
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path, limits));
  return ReadNiftiFromMemory(bytes, path.string(), limits);
}

}  // namespace vpm

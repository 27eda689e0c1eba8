#include "server/io/read_metaimage.h"

#include <algorithm>
#include <string>
#include <vector>

#include "server/io/gzip_stream.h"
#include "server/io/metaimage_header.h"
#include "server/common/prefix_status.h"
#include "server/io/convert_voxels.h"
#include "server/io/voxel_type.h"

namespace vpm {
namespace {

Result<VolumeGeometry> MetaImageGeometry(const MetaImageHeader& h) {
  const int n = h.ndims;
  VolumeGeometry g;
  g.dims = {h.dim_size[0], h.dim_size[1], n == 3 ? h.dim_size[2] : 1};
  if (!h.spacing.empty()) {
    if (static_cast<int>(h.spacing.size()) != n) {
      return absl::InvalidArgumentError(
          StrCat("ElementSpacing lists ", h.spacing.size(), " values but NDims is ", n));
    }
    for (int a = 0; a < n; ++a) g.spacing_mm[a] = h.spacing[a];
  }
  if (!h.offset.empty()) {
    if (static_cast<int>(h.offset.size()) != n) {
      return absl::InvalidArgumentError(
          StrCat("Offset lists ", h.offset.size(), " values but NDims is ", n));
    }
    for (int a = 0; a < n; ++a) g.origin_mm[a] = h.offset[a];
  }
  if (!h.transform.empty()) {
    if (static_cast<int>(h.transform.size()) != n * n) {
      return absl::InvalidArgumentError(StrCat("TransformMatrix lists ", h.transform.size(),
                                                     " values; NDims ", n, " needs ", n * n));
    }
    // As ITK's MetaImageIO: values [n*a, n*a + n) are the direction of axis a.
    for (int a = 0; a < n; ++a) {
      for (int r = 0; r < n; ++r) g.direction[a][r] = h.transform[n * a + r];
    }
  }
  return g;
}

// The stored bytes of the voxels: after HeaderSize (detached), inflated
// when compressed; at least `data_bytes` long.
Result<std::span<const uint8_t>> LocateData(const MetaImageHeader& h, std::span<const uint8_t> data,
                                            bool detached, int64_t data_bytes,
                                            const std::string& described,
                                            const VolumeLimits& limits,
                                            std::vector<uint8_t>& inflated) {
  const int64_t available = static_cast<int64_t>(data.size());
  int64_t skip = detached ? h.header_size : 0;
  if (skip == -1) {
    if (h.compressed) return absl::InvalidArgumentError("HeaderSize -1 needs uncompressed data");
    skip = std::max<int64_t>(available - data_bytes, 0);
  }
  if (skip > available) {
    return absl::InvalidArgumentError(StrCat("HeaderSize ", skip, " is past the end of the ",
                                                   available, "-byte data file"));
  }
  data = data.subspan(static_cast<size_t>(skip));
  if (h.compressed) {
    if (h.compressed_size >= 0 && h.compressed_size < static_cast<int64_t>(data.size())) {
      data = data.first(static_cast<size_t>(h.compressed_size));
    }
    Result<std::vector<uint8_t>> all = InflateExactly(data, data_bytes, limits);
    if (!all.ok()) return PrefixStatus(all.status(), described);
    inflated = std::move(*all);
    return std::span<const uint8_t>(inflated);
  }
  if (static_cast<int64_t>(data.size()) < data_bytes) {
    return absl::InvalidArgumentError(
        StrCat(described, " but the file holds ", data.size(), " bytes of data (truncated)"));
  }
  return data;
}

Result<Volume> DecodeMetaImage(std::span<const uint8_t> bytes, std::string_view name,
                               const VolumeLimits& limits, const DataFileLoader& loader) {
  ASSIGN_OR_RETURN(const MetaImageHeader header, ParseMetaImageHeader(bytes));
  ASSIGN_OR_RETURN(const VolumeGeometry geometry, MetaImageGeometry(header));
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits));
  const int64_t voxels = geometry.voxel_count();
  const int64_t data_bytes = voxels * VoxelTypeSize(header.type);
  const std::string described =
      StrCat("header says ", DescribeVoxelData(geometry.dims, header.type));
  if (data_bytes > limits.max_bytes) {
    return absl::ResourceExhaustedError(
        StrCat(described, ", over the cap of ", limits.max_bytes, " bytes"));
  }
  const bool detached = header.data_file != "LOCAL";
  std::vector<uint8_t> file_bytes;
  std::span<const uint8_t> data = bytes.subspan(static_cast<size_t>(header.data_offset));
  if (detached) {
    if (!loader) {
      return absl::InvalidArgumentError(StrCat(
          "detached ElementDataFile \"", header.data_file, "\" cannot be read here (no folder)"));
    }
    ASSIGN_OR_RETURN(file_bytes, loader(header.data_file));
    data = file_bytes;
  }
  std::vector<uint8_t> inflated;
  ASSIGN_OR_RETURN(const std::span<const uint8_t> stored,
                   LocateData(header, data, detached, data_bytes, described, limits, inflated));
  return VolumeFromStoredVoxels(stored, header.type, header.endian, geometry, limits, name);
}

}  // namespace

Result<Volume> ReadMetaImageFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                       const VolumeLimits& limits, const DataFileLoader& loader) {
  Result<Volume> volume = DecodeMetaImage(bytes, name, limits, loader);
  if (!volume.ok()) return PrefixStatus(volume.status(), name);
  return volume;
}

Result<Volume> ReadMetaImage(const std::filesystem::path& path, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path, limits));
  return ReadMetaImageFromMemory(bytes, path.string(), limits, SiblingFileLoader(path, limits));
}

}  // namespace vpm

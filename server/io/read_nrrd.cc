#include "server/io/read_nrrd.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "server/io/gzip_stream.h"
#include "server/io/header_text.h"
#include "server/io/nrrd_header.h"
#include "server/common/prefix_status.h"
#include "server/io/convert_voxels.h"
#include "server/io/voxel_type.h"

namespace vpm {
namespace {

// The matrix taking a NRRD space's coordinates to LPS.
Result<glm::dmat3> SpaceToLps(const NrrdHeader& h) {
  const std::string& s = h.space;
  if (s.empty()) {
    if (h.space_dimension != 0 && h.space_dimension != 3) {
      return absl::UnimplementedError(
          StrCat("space dimension ", h.space_dimension, " is not supported (only 3)"));
    }
    return glm::dmat3(1.0);  // no anatomical frame given: taken as LPS
  }
  if (s == "left-posterior-superior" || s == "lps") return glm::dmat3(1.0);
  if (s == "right-anterior-superior" || s == "ras") {
    return glm::dmat3(glm::dvec3(-1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1));
  }
  if (s == "left-anterior-superior" || s == "las") {
    return glm::dmat3(glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0), glm::dvec3(0, 0, 1));
  }
  for (const char* known :
       {"scanner-xyz", "3d-right-handed", "3d-left-handed", "right-anterior-superior-time",
        "left-anterior-superior-time", "left-posterior-superior-time", "rast", "last", "lpst",
        "scanner-xyz-time", "3d-right-handed-time", "3d-left-handed-time"}) {
    if (s == known) {
      return absl::UnimplementedError(StrCat("space \"", s, "\" is not supported"));
    }
  }
  return absl::InvalidArgumentError(StrCat("unknown space \"", s.substr(0, 40), "\""));
}

Status CheckAxes(const NrrdHeader& h) {
  if (h.dimension > 3) {
    return absl::UnimplementedError(StrCat("dimension is ", h.dimension,
                                                 "; only 2D and 3D scalar volumes are supported"));
  }
  if (h.dimension < 2) return absl::UnimplementedError("1D data is not supported");
  for (const std::string& kind : h.kinds) {
    if (kind != "domain" && kind != "space" && kind != "???" && kind != "none") {
      return absl::UnimplementedError(StrCat("axis kind \"", kind.substr(0, 40),
                                                   "\" is not supported (only scalar volumes)"));
    }
  }
  return absl::OkStatus();
}

Status DirectionsToGeometry(const NrrdHeader& h, VolumeGeometry& g) {
  if (static_cast<int>(h.space_directions.size()) != h.dimension) {
    return absl::InvalidArgumentError(StrCat("space directions lists ",
                                                   h.space_directions.size(),
                                                   " vectors but dimension is ", h.dimension));
  }
  for (int a = 0; a < h.dimension; ++a) {
    if (!h.space_directions[a].has_value()) {
      return absl::InvalidArgumentError(
          StrCat("space direction of axis ", a, " is none; all axes must be spatial"));
    }
    const glm::dvec3 d = *h.space_directions[a];
    const double length = glm::length(d);
    if (!std::isfinite(length) || length <= 0.0) {
      return absl::InvalidArgumentError(StrCat("space direction of axis ", a, " has length ",
                                                     length, "; the spacing must be positive"));
    }
    g.spacing_mm[a] = length;
    g.direction[a] = d / length;
  }
  if (h.dimension == 2) {
    const glm::dvec3 normal = glm::cross(g.direction[0], g.direction[1]);
    const double length = glm::length(normal);
    g.direction[2] = length > 0.0 ? normal / length : glm::dvec3(0.0);
  }
  return absl::OkStatus();
}

Result<VolumeGeometry> NrrdGeometry(const NrrdHeader& h) {
  RETURN_IF_ERROR(CheckAxes(h));
  ASSIGN_OR_RETURN(const glm::dmat3 to_lps, SpaceToLps(h));
  VolumeGeometry g;
  g.dims = {h.sizes[0], h.sizes[1], h.dimension == 3 ? h.sizes[2] : 1};
  if (!h.space_directions.empty()) {
    RETURN_IF_ERROR(DirectionsToGeometry(h, g));
  } else if (!h.spacings.empty()) {
    if (static_cast<int>(h.spacings.size()) != h.dimension) {
      return absl::InvalidArgumentError(StrCat("spacings lists ", h.spacings.size(),
                                                     " values but dimension is ", h.dimension));
    }
    for (int a = 0; a < h.dimension; ++a) g.spacing_mm[a] = h.spacings[a];
  }
  // Without space directions the axes have no stated orientation: identity.
  if (!h.space_directions.empty()) g.direction = to_lps * g.direction;
  if (h.space_origin.has_value()) g.origin_mm = to_lps * *h.space_origin;
  return g;
}

// Skips `lines` lines of `data`; nullopt when the data ends first.
std::optional<std::span<const uint8_t>> SkipLines(std::span<const uint8_t> data, int64_t lines) {
  size_t pos = 0;
  for (int64_t n = 0; n < lines; ++n) {
    while (pos < data.size() && data[pos] != '\n') ++pos;
    if (pos == data.size()) return std::nullopt;
    ++pos;
  }
  return data.subspan(pos);
}

Result<std::vector<float>> ParseAsciiValues(std::span<const uint8_t> data, int64_t count) {
  const std::string_view text(reinterpret_cast<const char*>(data.data()), data.size());
  std::vector<float> values;
  values.reserve(static_cast<size_t>(std::min<int64_t>(count, int64_t{1} << 20)));
  size_t n = 0;
  while (static_cast<int64_t>(values.size()) < count) {
    while (n < text.size() && (std::isspace(static_cast<unsigned char>(text[n])) || text[n] == ','))
      ++n;
    const size_t start = n;
    while (n < text.size() && !std::isspace(static_cast<unsigned char>(text[n])) && text[n] != ',')
      ++n;
    if (n == start) {
      return absl::InvalidArgumentError(StrCat("ascii data holds ", values.size(), " of the ",
                                                     count, " values (truncated)"));
    }
    const std::optional<double> value = ParseDouble(text.substr(start, n - start));
    if (!value.has_value()) {
      return absl::InvalidArgumentError(
          StrCat("ascii data: value ", values.size(), " is not a number"));
    }
    values.push_back(DoubleToFloat(*value));
  }
  return values;
}

Result<VoxelValues> DecodeData(const NrrdHeader& h, std::span<const uint8_t> data,
                               const VolumeGeometry& g, const VolumeLimits& limits,
                               std::string* float_note) {
  const int64_t voxels = g.voxel_count();
  const int64_t data_bytes = voxels * VoxelTypeSize(h.type);
  const std::string described = StrCat("header says ", DescribeVoxelData(g.dims, h.type));
  const std::optional<std::span<const uint8_t>> after_lines = SkipLines(data, h.line_skip);
  if (!after_lines.has_value()) {
    return absl::InvalidArgumentError(
        StrCat("data ends within the ", h.line_skip, " lines to skip (truncated)"));
  }
  data = *after_lines;
  if (h.encoding == NrrdEncoding::kAscii) {
    ASSIGN_OR_RETURN(std::vector<float> values, ParseAsciiValues(data, voxels));
    if (h.type == VoxelType::kFloat32 || h.type == VoxelType::kFloat64) {
      RETURN_IF_ERROR(ValidateGeometry(g, limits, VoxelEncoding::kFloat32));
      return VoxelValues::Float(std::move(values));
    }
    return FloatsToVoxels(std::move(values), g, limits, float_note);
  }
  std::vector<uint8_t> inflated;
  if (h.encoding == NrrdEncoding::kGzip) {
    Result<std::vector<uint8_t>> all = InflateExactly(data, h.byte_skip + data_bytes, limits);
    if (!all.ok()) return PrefixStatus(all.status(), described);
    inflated = std::move(*all);
    data = std::span<const uint8_t>(inflated).subspan(static_cast<size_t>(h.byte_skip));
  } else {
    const int64_t available = static_cast<int64_t>(data.size());
    const int64_t skip = h.byte_skip == -1 ? available - data_bytes : h.byte_skip;
    if (skip < 0 || available - skip < data_bytes) {
      return absl::InvalidArgumentError(
          StrCat(described, " after skipping ", std::max<int64_t>(skip, 0),
                       " bytes, but the data holds ", available, " bytes (truncated)"));
    }
    data = data.subspan(static_cast<size_t>(skip));
  }
  return ConvertVoxels(data, h.type, h.endian, g, limits, 1.0, 0.0, float_note);
}

Result<Volume> DecodeNrrd(std::span<const uint8_t> bytes, std::string_view name,
                          const VolumeLimits& limits, const DataFileLoader& loader) {
  ASSIGN_OR_RETURN(const NrrdHeader header, ParseNrrdHeader(bytes));
  ASSIGN_OR_RETURN(const VolumeGeometry geometry, NrrdGeometry(header));
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits));
  const int64_t data_bytes = geometry.voxel_count() * VoxelTypeSize(header.type);
  if (data_bytes > limits.max_bytes - std::max<int64_t>(header.byte_skip, 0)) {
    return absl::ResourceExhaustedError(
        StrCat("header says ", DescribeVoxelData(geometry.dims, header.type),
                     ", over the cap of ", limits.max_bytes, " bytes"));
  }
  std::vector<uint8_t> detached;
  std::span<const uint8_t> data = bytes.subspan(static_cast<size_t>(header.data_offset));
  if (!header.data_file.empty()) {
    if (!loader) {
      return absl::InvalidArgumentError(StrCat("detached data file \"", header.data_file,
                                                     "\" cannot be read here (no folder)"));
    }
    ASSIGN_OR_RETURN(detached, loader(header.data_file));
    data = detached;
  }
  std::string note;
  ASSIGN_OR_RETURN(VoxelValues values, DecodeData(header, data, geometry, limits, &note));
  detached = {};
  ASSIGN_OR_RETURN(Volume volume, Volume::Create(geometry, std::move(values), limits));
  volume.set_source(std::string(name));
  if (!note.empty()) volume.add_note(std::move(note));
  return volume;
}

}  // namespace

Result<Volume> ReadNrrdFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                  const VolumeLimits& limits, const DataFileLoader& loader) {
  Result<Volume> volume = DecodeNrrd(bytes, name, limits, loader);
  if (!volume.ok()) return PrefixStatus(volume.status(), name);
  return volume;
}

Result<Volume> ReadNrrd(const std::filesystem::path& path, const VolumeLimits& limits) {
  ASSIGN_OR_RETURN(const std::vector<uint8_t> bytes, ReadFileBytes(path, limits));
  return ReadNrrdFromMemory(bytes, path.string(), limits, SiblingFileLoader(path, limits));
}

}  // namespace vpm

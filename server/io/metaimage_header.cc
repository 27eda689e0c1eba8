#include "server/io/metaimage_header.h"

#include <algorithm>
#include <map>
#include <optional>
#include <set>
#include <string_view>

#include "server/io/header_text.h"

namespace vpm {
namespace {

// MetaIO's MET_* element types (MET_LONG / MET_ULONG are 4 bytes there).
Status ParseElementType(std::string_view value, MetaImageHeader& h) {
  static const std::map<std::string, VoxelType, std::less<>> kTypes = {
      {"MET_UCHAR", VoxelType::kUint8},       {"MET_CHAR", VoxelType::kInt8},
      {"MET_USHORT", VoxelType::kUint16},     {"MET_SHORT", VoxelType::kInt16},
      {"MET_UINT", VoxelType::kUint32},       {"MET_INT", VoxelType::kInt32},
      {"MET_ULONG", VoxelType::kUint32},      {"MET_LONG", VoxelType::kInt32},
      {"MET_ULONG_LONG", VoxelType::kUint64}, {"MET_LONG_LONG", VoxelType::kInt64},
      {"MET_FLOAT", VoxelType::kFloat32},     {"MET_DOUBLE", VoxelType::kFloat64},
  };
  const auto it = kTypes.find(value);
  if (it != kTypes.end()) {
    h.type = it->second;
    return absl::OkStatus();
  }
  if (value.starts_with("MET_")) {
    return absl::UnimplementedError(StrCat("ElementType ", std::string(value.substr(0, 40)),
                                                 " is not supported (scalar types only)"));
  }
  return absl::InvalidArgumentError(
      StrCat("unknown ElementType \"", std::string(value.substr(0, 40)), "\""));
}

Result<bool> ParseBool(std::string_view value, std::string_view key) {
  const std::string v = ToLowerAscii(value);
  if (v == "true" || v == "1") return true;
  if (v == "false" || v == "0") return false;
  return absl::InvalidArgumentError(StrCat(std::string(key), " must be True or False"));
}

Result<int64_t> ParseSize(std::string_view value, std::string_view key, int64_t min) {
  const std::optional<int64_t> n = ParseInt(value);
  if (!n.has_value() || *n < min) {
    return absl::InvalidArgumentError(
        StrCat(std::string(key), " must be an integer >= ", min));
  }
  return *n;
}

Status ParseSimpleField(const std::string& key, std::string_view value, MetaImageHeader& h) {
  if (key == "ObjectType") {
    if (ToLowerAscii(value) != "image") {
      return absl::InvalidArgumentError(
          StrCat("ObjectType is \"", std::string(value.substr(0, 40)), "\", not Image"));
    }
  } else if (key == "NDims") {
    ASSIGN_OR_RETURN(const int64_t n, ParseSize(value, key, 1));
    h.ndims = static_cast<int>(std::min<int64_t>(n, 1000));
  } else if (key == "BinaryData") {
    ASSIGN_OR_RETURN(const bool binary, ParseBool(value, key));
    if (!binary)
      return absl::UnimplementedError("ASCII data (BinaryData = False) is not supported");
  } else if (key == "ElementByteOrderMSB" || key == "BinaryDataByteOrderMSB") {
    ASSIGN_OR_RETURN(const bool msb, ParseBool(value, key));
    h.endian = msb ? Endian::kBig : Endian::kLittle;
  } else if (key == "CompressedData") {
    ASSIGN_OR_RETURN(h.compressed, ParseBool(value, key));
  } else if (key == "CompressedDataSize") {
    ASSIGN_OR_RETURN(h.compressed_size, ParseSize(value, key, 0));
  } else if (key == "HeaderSize") {
    ASSIGN_OR_RETURN(h.header_size, ParseSize(value, key, -1));
  } else if (key == "ElementNumberOfChannels") {
    ASSIGN_OR_RETURN(const int64_t channels, ParseSize(value, key, 1));
    if (channels != 1) {
      return absl::UnimplementedError(
          StrCat("ElementNumberOfChannels is ", channels, "; only scalar volumes"));
    }
  } else if (key == "ElementType") {
    return ParseElementType(value, h);
  }
  return absl::OkStatus();  // other keys (AnatomicalOrientation, ...) are ignored
}

Status ParseField(const std::string& key, std::string_view value, MetaImageHeader& h) {
  if (key == "DimSize") {
    ASSIGN_OR_RETURN(h.dim_size, ParseIntList(value, key));
  } else if (key == "ElementSpacing" || (key == "ElementSize" && h.spacing.empty())) {
    ASSIGN_OR_RETURN(h.spacing, ParseDoubleList(value, key));
  } else if (key == "Offset" || key == "Origin" || key == "Position") {
    ASSIGN_OR_RETURN(h.offset, ParseDoubleList(value, key));
  } else if (key == "TransformMatrix" || key == "Rotation" || key == "Orientation") {
    ASSIGN_OR_RETURN(h.transform, ParseDoubleList(value, key));
  } else {
    return ParseSimpleField(key, value, h);
  }
  return absl::OkStatus();
}

Status ParseDataFile(std::string_view value, MetaImageHeader& h) {
  if (value.empty()) return absl::InvalidArgumentError("ElementDataFile is empty");
  if (value.starts_with("LIST") || value.find('%') != std::string_view::npos) {
    return absl::UnimplementedError(
        "ElementDataFile LIST or a file name pattern (one file per slice) is not supported");
  }
  h.data_file = std::string(value);
  return absl::OkStatus();
}

Status CheckRequired(const MetaImageHeader& h) {
  if (h.ndims == 0) return absl::InvalidArgumentError("NDims is missing");
  if (h.ndims > 3) {
    return absl::UnimplementedError(
        StrCat("NDims is ", h.ndims, "; only 2D and 3D volumes are supported"));
  }
  if (h.ndims < 2) return absl::UnimplementedError("1D data is not supported");
  if (static_cast<int>(h.dim_size.size()) != h.ndims) {
    return absl::InvalidArgumentError(
        StrCat("DimSize lists ", h.dim_size.size(), " sizes but NDims is ", h.ndims));
  }
  return absl::OkStatus();
}

}  // namespace

Result<MetaImageHeader> ParseMetaImageHeader(std::span<const uint8_t> bytes) {
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  MetaImageHeader h;
  std::set<std::string> seen;
  bool element_type = false;
  size_t pos = 0;
  int64_t line_number = 0;
  while (const std::optional<std::string_view> line = NextLine(text, &pos)) {
    ++line_number;
    if (TrimAscii(*line).empty()) continue;
    const size_t equals = line->find('=');
    if (equals == std::string_view::npos) {
      return absl::InvalidArgumentError(StrCat(
          "header line ", line_number, " is not \"Key = Value\" (not a MetaImage file?)"));
    }
    const std::string key(TrimAscii(line->substr(0, equals)));
    const std::string_view value = TrimAscii(line->substr(equals + 1));
    if (!seen.insert(key).second) {
      return absl::InvalidArgumentError(
          StrCat("header line ", line_number, ": ", key.substr(0, 40), " appears twice"));
    }
    if (key == "ElementDataFile") {
      RETURN_IF_ERROR(ParseDataFile(value, h));
      if (!element_type) return absl::InvalidArgumentError("ElementType is missing");
      RETURN_IF_ERROR(CheckRequired(h));
      h.data_offset = static_cast<int64_t>(pos);
      return h;
    }
    element_type = element_type || key == "ElementType";
    const Status status = ParseField(key, value, h);
    if (!status.ok()) {
      return Status(status.code(),
                    StrCat("header line ", line_number, ": ", status.message()));
    }
  }
  return absl::InvalidArgumentError("header has no ElementDataFile line (truncated?)");
}

}  // namespace vpm

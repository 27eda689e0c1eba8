#include "server/io/nrrd_header.h"

#include <algorithm>
#include <map>
#include <set>
#include <string_view>

#include "server/io/header_text.h"

namespace vpm {
namespace {

// NRRD's many spellings of each type (format spec, "type").
std::optional<VoxelType> NrrdType(const std::string& name) {
  static const std::map<std::string, VoxelType, std::less<>> kTypes = {
      {"signed char", VoxelType::kInt8},
      {"int8", VoxelType::kInt8},
      {"int8_t", VoxelType::kInt8},
      {"uchar", VoxelType::kUint8},
      {"unsigned char", VoxelType::kUint8},
      {"uint8", VoxelType::kUint8},
      {"uint8_t", VoxelType::kUint8},
      {"short", VoxelType::kInt16},
      {"short int", VoxelType::kInt16},
      {"signed short", VoxelType::kInt16},
      {"signed short int", VoxelType::kInt16},
      {"int16", VoxelType::kInt16},
      {"int16_t", VoxelType::kInt16},
      {"ushort", VoxelType::kUint16},
      {"unsigned short", VoxelType::kUint16},
      {"unsigned short int", VoxelType::kUint16},
      {"uint16", VoxelType::kUint16},
      {"uint16_t", VoxelType::kUint16},
      {"int", VoxelType::kInt32},
      {"signed int", VoxelType::kInt32},
      {"int32", VoxelType::kInt32},
      {"int32_t", VoxelType::kInt32},
      {"uint", VoxelType::kUint32},
      {"unsigned int", VoxelType::kUint32},
      {"uint32", VoxelType::kUint32},
      {"uint32_t", VoxelType::kUint32},
      {"longlong", VoxelType::kInt64},
      {"long long", VoxelType::kInt64},
      {"long long int", VoxelType::kInt64},
      {"signed long long", VoxelType::kInt64},
      {"signed long long int", VoxelType::kInt64},
      {"int64", VoxelType::kInt64},
      {"int64_t", VoxelType::kInt64},
      {"ulonglong", VoxelType::kUint64},
      {"unsigned long long", VoxelType::kUint64},
      {"unsigned long long int", VoxelType::kUint64},
      {"uint64", VoxelType::kUint64},
      {"uint64_t", VoxelType::kUint64},
      {"float", VoxelType::kFloat32},
      {"double", VoxelType::kFloat64},
  };
  const auto it = kTypes.find(name);
  if (it == kTypes.end()) return std::nullopt;
  return it->second;
}

// "(1.5,0,0)" -> the vector; "none" -> nullopt.
Result<std::optional<glm::dvec3>> ParseVector(std::string_view token, std::string_view what) {
  if (token == "none") return std::optional<glm::dvec3>();
  if (token.size() < 2 || token.front() != '(' || token.back() != ')') {
    return absl::InvalidArgumentError(
        StrCat(std::string(what), ": expected \"(x,y,z)\" or \"none\""));
  }
  ASSIGN_OR_RETURN(const std::vector<double> values,
                   ParseDoubleList(token.substr(1, token.size() - 2), what));
  if (values.size() != 3) {
    return absl::InvalidArgumentError(StrCat(
        std::string(what), ": vectors need 3 components (a 3D space), got ", values.size()));
  }
  return std::optional<glm::dvec3>(glm::dvec3(values[0], values[1], values[2]));
}

// Vectors are separated by spaces; "(1, 0, 0)" may hold spaces of its own.
Result<std::vector<std::optional<glm::dvec3>>> ParseVectors(std::string_view text,
                                                            std::string_view what) {
  std::vector<std::optional<glm::dvec3>> vectors;
  size_t n = 0;
  while (true) {
    while (n < text.size() && (text[n] == ' ' || text[n] == '\t')) ++n;
    if (n >= text.size()) break;
    size_t end = text[n] == '(' ? text.find(')', n) : text.find_first_of(" \t", n);
    end = end == std::string_view::npos ? text.size() : end + (text[n] == '(' ? 1 : 0);
    ASSIGN_OR_RETURN(auto vector, ParseVector(text.substr(n, end - n), what));
    vectors.push_back(vector);
    n = end;
  }
  return vectors;
}

Status ParseEncoding(const std::string& value, NrrdHeader& h) {
  if (value == "raw") {
    h.encoding = NrrdEncoding::kRaw;
  } else if (value == "gzip" || value == "gz") {
    h.encoding = NrrdEncoding::kGzip;
  } else if (value == "ascii" || value == "text" || value == "txt") {
    h.encoding = NrrdEncoding::kAscii;
  } else if (value == "bzip2" || value == "bz2" || value == "hex" || value == "zrl") {
    return absl::UnimplementedError(
        StrCat("encoding ", QuoteForMessage(value), " is not supported"));
  } else {
    return absl::InvalidArgumentError(StrCat("unknown encoding ", QuoteForMessage(value)));
  }
  return absl::OkStatus();
}

Result<int64_t> ParseCount(std::string_view value, std::string_view field, int64_t min) {
  const std::optional<int64_t> n = ParseInt(value);
  if (!n.has_value() || *n < min) {
    return absl::InvalidArgumentError(
        StrCat(std::string(field), " must be an integer >= ", min));
  }
  return *n;
}

Status ParseType(const std::string& value, NrrdHeader& h) {
  if (value == "block") {
    return absl::UnimplementedError("type \"block\" is not supported");
  }
  const std::optional<VoxelType> type = NrrdType(value);
  if (!type.has_value()) {
    return absl::InvalidArgumentError(StrCat("unknown type ", QuoteForMessage(value)));
  }
  h.type = *type;
  return absl::OkStatus();
}

Status ParseDataFile(std::string_view value, NrrdHeader& h) {
  if (value.starts_with("LIST") || value.find('%') != std::string_view::npos ||
      SplitTokens(value).size() > 1) {
    return absl::UnimplementedError(
        "data split over several files (LIST or a name pattern) is not supported");
  }
  h.data_file = std::string(value);
  return absl::OkStatus();
}

Status ParseGeometryField(const std::string& key, std::string_view value, NrrdHeader& h) {
  if (key == "space") {
    h.space = ToLowerAscii(value);
  } else if (key == "space dimension") {
    ASSIGN_OR_RETURN(const int64_t n, ParseCount(value, key, 1));
    h.space_dimension = static_cast<int>(std::min<int64_t>(n, 1000));
  } else if (key == "space directions") {
    ASSIGN_OR_RETURN(h.space_directions, ParseVectors(value, key));
  } else if (key == "space origin") {
    ASSIGN_OR_RETURN(const auto origin, ParseVector(value, key));
    if (!origin.has_value()) return absl::InvalidArgumentError("space origin cannot be none");
    h.space_origin = origin;
  } else if (key == "spacings") {
    ASSIGN_OR_RETURN(h.spacings, ParseDoubleList(value, key));
  } else if (key == "kinds") {
    for (std::string_view kind : SplitTokens(value)) h.kinds.emplace_back(kind);
  }
  return absl::OkStatus();
}

Status ParseField(const std::string& key, std::string_view value, NrrdHeader& h) {
  if (key == "dimension") {
    ASSIGN_OR_RETURN(const int64_t n, ParseCount(value, key, 1));
    h.dimension = static_cast<int>(std::min<int64_t>(n, 1000));
  } else if (key == "sizes") {
    ASSIGN_OR_RETURN(h.sizes, ParseIntList(value, key));
  } else if (key == "type") {
    RETURN_IF_ERROR(ParseType(ToLowerAscii(value), h));
  } else if (key == "endian") {
    const std::string e = ToLowerAscii(value);
    if (e != "little" && e != "big") {
      return absl::InvalidArgumentError("endian must be \"little\" or \"big\"");
    }
    h.endian = e == "big" ? Endian::kBig : Endian::kLittle;
    h.endian_given = true;
  } else if (key == "encoding") {
    RETURN_IF_ERROR(ParseEncoding(ToLowerAscii(value), h));
  } else if (key == "data file" || key == "datafile") {
    RETURN_IF_ERROR(ParseDataFile(value, h));
  } else if (key == "line skip" || key == "lineskip") {
    ASSIGN_OR_RETURN(h.line_skip, ParseCount(value, key, 0));
  } else if (key == "byte skip" || key == "byteskip") {
    ASSIGN_OR_RETURN(h.byte_skip, ParseCount(value, key, -1));
  } else {
    return ParseGeometryField(key, value, h);  // others are ignored there
  }
  return absl::OkStatus();
}

Status CheckRequired(const std::set<std::string>& seen, const NrrdHeader& h) {
  for (const char* key : {"dimension", "sizes", "type", "encoding"}) {
    if (seen.count(key) == 0) {
      return absl::InvalidArgumentError(StrCat("required field \"", key, "\" is missing"));
    }
  }
  if (static_cast<int>(h.sizes.size()) != h.dimension) {
    return absl::InvalidArgumentError(
        StrCat("sizes lists ", h.sizes.size(), " axes but dimension is ", h.dimension));
  }
  if (!h.endian_given && VoxelTypeSize(h.type) > 1 && h.encoding != NrrdEncoding::kAscii) {
    return absl::InvalidArgumentError("endian is missing for a multi-byte type");
  }
  if (h.byte_skip == -1 && h.encoding != NrrdEncoding::kRaw) {
    return absl::InvalidArgumentError("byte skip -1 is only allowed with raw encoding");
  }
  return absl::OkStatus();
}

// Splits "key: value" (or "key:=value", a key/value pair we ignore).
Status ParseLine(std::string_view line, std::set<std::string>& seen, NrrdHeader& h) {
  if (line.empty() || line.front() == '#') return absl::OkStatus();
  const size_t colon = line.find(':');
  if (colon == std::string_view::npos) {
    return absl::InvalidArgumentError("header line without a \"field: value\" form");
  }
  if (colon + 1 < line.size() && line[colon + 1] == '=') return absl::OkStatus();
  const std::string key(TrimAscii(line.substr(0, colon)));
  if (!seen.insert(key).second) {
    return absl::InvalidArgumentError(
        StrCat("field \"", key.substr(0, 40), "\" appears twice"));
  }
  return ParseField(key, TrimAscii(line.substr(colon + 1)), h);
}

}  // namespace

Result<NrrdHeader> ParseNrrdHeader(std::span<const uint8_t> bytes) {
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  size_t pos = 0;
  const std::optional<std::string_view> magic = NextLine(text, &pos);
  if (!magic.has_value() || magic->size() != 8 || !magic->starts_with("NRRD000") ||
      (*magic)[7] < '1' || (*magic)[7] > '5') {
    return absl::InvalidArgumentError(
        "wrong magic: not a NRRD file (expected \"NRRD0001\"..\"NRRD0005\")");
  }
  NrrdHeader h;
  std::set<std::string> seen;
  bool blank_line = false;
  int64_t line_number = 1;
  while (const std::optional<std::string_view> line = NextLine(text, &pos)) {
    ++line_number;
    if (line->empty()) {
      blank_line = true;
      break;
    }
    const Status status = ParseLine(*line, seen, h);
    if (!status.ok()) {
      return Status(status.code(),
                    StrCat("header line ", line_number, ": ", status.message()));
    }
  }
  if (!blank_line && h.data_file.empty()) {
    return absl::InvalidArgumentError(
        "header does not end with a blank line and names no data file (truncated?)");
  }
  RETURN_IF_ERROR(CheckRequired(seen, h));
  h.data_offset = static_cast<int64_t>(pos);
  return h;
}

}  // namespace vpm

#include "server/io/parse_raw_source.h"

#include <optional>
#include <set>
#include <vector>

#include "server/io/header_text.h"
#include "server/io/parse_source_query.h"

namespace vpm {
namespace {

constexpr std::string_view kRawSyntax =
    "raw:PATH?dims=X,Y,Z&type=int16&spacing=A,B,C[&endian=little|big][&offset=N]";

Status Bad(std::string_view what) {
  return absl::InvalidArgumentError(
      StrCat("raw source: ", std::string(what), " (syntax: ", std::string(kRawSyntax), ")"));
}

Status ParseParam(std::string_view key, std::string_view value, RawOptions& options) {
  if (key == "dims") {
    ASSIGN_OR_RETURN(const std::vector<int64_t> dims, ParseIntList(value, "dims"));
    if (dims.size() != 3) return Bad("dims needs 3 integers");
    options.dims = {dims[0], dims[1], dims[2]};
  } else if (key == "type") {
    const std::optional<VoxelType> type = VoxelTypeFromName(value);
    if (!type.has_value())
      return Bad(StrCat("unknown type \"", std::string(value.substr(0, 40)), "\""));
    options.type = *type;
  } else if (key == "spacing") {
    ASSIGN_OR_RETURN(const std::vector<double> spacing, ParseDoubleList(value, "spacing"));
    if (spacing.size() != 3) return Bad("spacing needs 3 numbers (mm)");
    options.spacing_mm = {spacing[0], spacing[1], spacing[2]};
  } else if (key == "endian") {
    if (value != "little" && value != "big") return Bad("endian must be little or big");
    options.endian = value == "big" ? Endian::kBig : Endian::kLittle;
  } else if (key == "offset") {
    const std::optional<int64_t> offset = ParseInt(value);
    if (!offset.has_value() || *offset < 0) return Bad("offset must be an integer >= 0");
    options.header_offset_bytes = *offset;
  } else {
    return Bad(StrCat("unknown key \"", std::string(key.substr(0, 40)), "\""));
  }
  return absl::OkStatus();
}

}  // namespace

Result<RawSource> ParseRawSource(std::string_view source) {
  if (!source.starts_with("raw:")) return Bad("must start with \"raw:\"");
  source.remove_prefix(4);
  const size_t question = source.rfind('?');
  if (question == std::string_view::npos) return Bad("missing \"?\" and parameters");
  RawSource out;
  out.path = std::string(source.substr(0, question));
  if (out.path.empty()) return Bad("empty path");
  Result<std::vector<SourceParam>> params = ParseSourceQuery(source.substr(question + 1));
  if (!params.ok()) return Bad(std::string(params.status().message()));
  std::set<std::string_view> seen;
  for (const auto& [key, value] : *params) {
    seen.insert(key);
    RETURN_IF_ERROR(ParseParam(key, value, out.options));
  }
  for (const char* required : {"dims", "type", "spacing"}) {
    if (seen.count(std::string_view(required)) == 0) {
      return Bad(StrCat("\"", required, "\" is required"));
    }
  }
  return out;
}

}  // namespace vpm

#include "server/io/parse_dicom_source.h"

#include <cmath>
#include <system_error>

#include "server/io/header_text.h"
#include "server/io/parse_source_query.h"

namespace vpm {
namespace {

constexpr std::string_view kDicomSyntax = "FOLDER[?series=UID|N][&stack=N][&spacing=MM]";

bool IsFolder(std::string_view path) {
  std::error_code ec;
  return !path.empty() && std::filesystem::is_directory(std::filesystem::path(path), ec);
}

Status Bad(std::string_view folder, std::string_view what) {
  return absl::InvalidArgumentError(StrCat("DICOM source ", std::string(folder), ": ",
                                           std::string(what), " (syntax: ", std::string(kDicomSyntax),
                                           ")"));
}

}  // namespace

std::optional<int64_t> ParseStackNumber(std::string_view text) {
  const std::optional<int64_t> n = ParseInt(text);
  if (!n.has_value() || *n < 1 || *n > kMaxDicomStack) return std::nullopt;
  return n;
}

Result<std::optional<DicomSource>> ParseDicomSource(std::string_view source) {
  if (IsFolder(source)) return DicomSource{std::filesystem::path(source), {}};
  const size_t question = source.rfind('?');
  if (question == std::string_view::npos || !IsFolder(source.substr(0, question))) {
    return std::optional<DicomSource>();
  }
  const std::string_view folder = source.substr(0, question);
  DicomSource out{std::filesystem::path(folder), {}};
  Result<std::vector<SourceParam>> params = ParseSourceQuery(source.substr(question + 1));
  if (!params.ok()) return Bad(folder, std::string(params.status().message()));
  for (const auto& [key, value] : *params) {
    if (key == "series") {
      if (value.empty()) return Bad(folder, "series is empty");
      out.options.series = std::string(value);
    } else if (key == "stack") {
      const std::optional<int64_t> stack = ParseStackNumber(value);
      if (!stack.has_value()) return Bad(folder, "stack must be a whole number >= 1");
      out.options.stack = *stack;
    } else if (key == "spacing") {
      const std::optional<double> mm = ParseDouble(value);
      if (!mm.has_value() || !std::isfinite(*mm) || !(*mm > 0.0)) {
        return Bad(folder, "spacing must be a number of mm > 0");
      }
      out.options.spacing_mm = *mm;
    } else {
      return Bad(folder, StrCat("unknown key \"", std::string(key.substr(0, 40)), "\""));
    }
  }
  return std::optional<DicomSource>(std::move(out));
}

}  // namespace vpm

#include "server/pacs/pacs_source.h"

#include "server/io/parse_dicom_source.h"
#include "server/io/parse_source_query.h"
#include "server/pacs/pacs_endpoint.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {

Result<PacsSource> ParsePacsSource(std::string_view source) {
  const auto bad = [](std::string_view why) {
    return absl::InvalidArgumentError(
        StrCat("source: ", why, "; a PACS series is pacs:ENDPOINT/STUDY_UID/SERIES_UID[?stack=N]"));
  };
  if (!source.starts_with(kPacsPrefix)) return bad("not a pacs: source");
  std::string_view rest = source.substr(kPacsPrefix.size());
  int64_t stack = 0;
  if (const size_t question = rest.find('?'); question != std::string_view::npos) {
    const Result<std::vector<SourceParam>> params = ParseSourceQuery(rest.substr(question + 1));
    rest = rest.substr(0, question);
    const std::optional<int64_t> n =
        params.ok() && params->size() == 1 && (*params)[0].first == "stack"
            ? ParseStackNumber((*params)[0].second)
            : std::nullopt;
    if (!n.has_value()) return bad("the query is not stack=N (N a whole number >= 1)");
    stack = *n;
  }
  const size_t first = rest.find('/');
  if (first == std::string_view::npos) return bad("no study UID");
  const size_t second = rest.find('/', first + 1);
  if (second == std::string_view::npos) return bad("no series UID");
  PacsSource out{std::string(rest.substr(0, first)),
                 std::string(rest.substr(first + 1, second - first - 1)),
                 std::string(rest.substr(second + 1)), stack};
  if (!CheckEndpointName(out.endpoint).ok()) return bad("a bad endpoint name");
  if (!CheckUid(out.study_uid, "").ok()) return bad("the study UID is not 1-64 digits and dots");
  if (!CheckUid(out.series_uid, "").ok()) return bad("the series UID is not 1-64 digits and dots");
  return out;
}

}  // namespace vpm::pacs

#include "server/io/parse_source_query.h"

#include <set>
#include <string>

namespace vpm {

Result<std::vector<SourceParam>> ParseSourceQuery(std::string_view query) {
  std::vector<SourceParam> params;
  std::set<std::string_view> seen;
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view param = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    const size_t equals = param.find('=');
    if (equals == std::string_view::npos) {
      return absl::InvalidArgumentError("parameters are key=value");
    }
    const std::string_view key = param.substr(0, equals);
    if (!seen.insert(key).second) {
      return absl::InvalidArgumentError(
          StrCat("\"", std::string(key.substr(0, 40)), "\" given twice"));
    }
    params.emplace_back(key, param.substr(equals + 1));
  }
  return params;
}

}  // namespace vpm

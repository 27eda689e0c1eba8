// The "?key=value&key=value" options that follow a volume source's path.
#pragma once

#include <string_view>
#include <utility>
#include <vector>

#include "server/common/status.h"

namespace vpm {

using SourceParam = std::pair<std::string_view, std::string_view>;  // key, value

// Splits `query` (the text after the '?', without it) into key=value pairs,
// in order; the views point into `query`. An empty query gives no pairs.
// InvalidArgument for a parameter without '=' or a key given twice.
Result<std::vector<SourceParam>> ParseSourceQuery(std::string_view query);

}  // namespace vpm

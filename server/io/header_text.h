// Small, strict parsers for the text headers of NRRD and MetaImage files.
// Each accepts a whole token or list and nothing else (no trailing junk).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"

namespace vpm {

// `text` quoted for an error message, shortened to 40 bytes (then "...",
// and its length): hostile files can hold megabyte-long tokens.
std::string QuoteForMessage(std::string_view text, char quote = '"');

std::string_view TrimAscii(std::string_view text);
std::string ToLowerAscii(std::string_view text);

// The line starting at `*pos` (without its "\n" or "\r\n"); advances `*pos`
// past the line end. Returns nullopt at the end of `text`.
std::optional<std::string_view> NextLine(std::string_view text, size_t* pos);

// Whole-token numbers: "12", "-3", "+4.5e-2", "nan", "inf".
std::optional<int64_t> ParseInt(std::string_view token);
std::optional<double> ParseDouble(std::string_view token);

// Tokens separated by spaces, tabs or commas.
std::vector<std::string_view> SplitTokens(std::string_view text);

// Lists of numbers: `what` names the field in the error messages.
Result<std::vector<int64_t>> ParseIntList(std::string_view text, std::string_view what);
Result<std::vector<double>> ParseDoubleList(std::string_view text, std::string_view what);

}  // namespace vpm

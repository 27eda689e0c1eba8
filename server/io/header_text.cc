#include "server/io/header_text.h"

#include <charconv>

namespace vpm {
namespace {

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

}  // namespace

std::string QuoteForMessage(std::string_view text, char quote) {
  constexpr size_t kMax = 40;
  const std::string_view q(&quote, 1);
  if (text.size() <= kMax) return StrCat(q, text, q);
  return StrCat(q, text.substr(0, kMax), "...", q, " (", text.size(), " bytes)");
}

std::string_view TrimAscii(std::string_view text) {
  while (!text.empty() && IsSpace(text.front())) text.remove_prefix(1);
  while (!text.empty() && IsSpace(text.back())) text.remove_suffix(1);
  return text;
}

std::string ToLowerAscii(std::string_view text) {
  std::string out(text);
  for (char& c : out) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return out;
}

std::optional<std::string_view> NextLine(std::string_view text, size_t* pos) {
  if (*pos >= text.size()) return std::nullopt;
  const size_t end = text.find('\n', *pos);
  std::string_view line = text.substr(*pos, end == std::string_view::npos ? end : end - *pos);
  *pos = end == std::string_view::npos ? text.size() : end + 1;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

std::optional<int64_t> ParseInt(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size()) {
    return std::nullopt;
  }
  return value;
}

std::optional<double> ParseDouble(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size()) {
    return std::nullopt;
  }
  return value;
}

std::vector<std::string_view> SplitTokens(std::string_view text) {
  std::vector<std::string_view> tokens;
  size_t n = 0;
  while (n < text.size()) {
    while (n < text.size() && (IsSpace(text[n]) || text[n] == ',')) ++n;
    const size_t start = n;
    while (n < text.size() && !IsSpace(text[n]) && text[n] != ',') ++n;
    if (n > start) tokens.push_back(text.substr(start, n - start));
  }
  return tokens;
}

Result<std::vector<int64_t>> ParseIntList(std::string_view text, std::string_view what) {
  std::vector<int64_t> values;
  for (std::string_view token : SplitTokens(text)) {
    const std::optional<int64_t> value = ParseInt(token);
    if (!value.has_value()) {
      return absl::InvalidArgumentError(
          StrCat(std::string(what), ": ", QuoteForMessage(token), " is not an integer"));
    }
    values.push_back(*value);
  }
  return values;
}

Result<std::vector<double>> ParseDoubleList(std::string_view text, std::string_view what) {
  std::vector<double> values;
  for (std::string_view token : SplitTokens(text)) {
    const std::optional<double> value = ParseDouble(token);
    if (!value.has_value()) {
      return absl::InvalidArgumentError(
          StrCat(std::string(what), ": ", QuoteForMessage(token), " is not a number"));
    }
    values.push_back(*value);
  }
  return values;
}

}  // namespace vpm

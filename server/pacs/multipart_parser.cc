#include "server/pacs/multipart_parser.h"

#include <algorithm>
#include <cctype>

namespace vpm::pacs {
namespace {

std::string Lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string_view Trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

}  // namespace

Result<std::string> MultipartBoundary(std::string_view content_type) {
  const size_t semicolon = content_type.find(';');
  const std::string type = Lower(Trim(content_type.substr(0, semicolon)));
  if (!type.starts_with("multipart/")) {
    return absl::InvalidArgumentError(StrCat("multipart: the answer's Content-Type is '",
                                             type.substr(0, 60), "', not multipart/related"));
  }
  size_t at = semicolon;
  while (at != std::string_view::npos && at < content_type.size()) {
    ++at;  // past ';'
    const size_t equals = content_type.find('=', at);
    if (equals == std::string_view::npos) break;
    const std::string name = Lower(Trim(content_type.substr(at, equals - at)));
    size_t value_begin = equals + 1;
    while (value_begin < content_type.size() && content_type[value_begin] == ' ') ++value_begin;
    std::string value;
    size_t next;
    if (value_begin < content_type.size() && content_type[value_begin] == '"') {
      // A quoted string: backslash escapes the next character.
      size_t i = value_begin + 1;
      bool closed = false;
      for (; i < content_type.size(); ++i) {
        if (content_type[i] == '\\' && i + 1 < content_type.size()) {
          value += content_type[++i];
        } else if (content_type[i] == '"') {
          closed = true;
          break;
        } else {
          value += content_type[i];
        }
      }
      if (!closed)
        return absl::InvalidArgumentError(
            "multipart: unterminated quoted parameter in Content-Type");
      next = content_type.find(';', i);
    } else {
      next = content_type.find(';', value_begin);
      value = std::string(Trim(content_type.substr(value_begin, next == std::string_view::npos
                                                                    ? std::string_view::npos
                                                                    : next - value_begin)));
    }
    if (name == "boundary") {
      if (value.empty() || value.size() > 200) {
        return absl::InvalidArgumentError(
            StrCat("multipart: the boundary is ", value.size(), " bytes; 1 to 200 expected"));
      }
      return value;
    }
    at = next;
  }
  return absl::InvalidArgumentError("multipart: the Content-Type names no boundary");
}

MultipartParser::MultipartParser(std::string boundary, Callbacks callbacks)
    // The body's first delimiter may come without the CRLF before it; the
    // buffer starts with one so that every delimiter looks the same.
    : delimiter_("\r\n--" + boundary), callbacks_(std::move(callbacks)), buffer_("\r\n") {}

Status MultipartParser::Feed(std::string_view bytes) {
  total_bytes_ += static_cast<int64_t>(bytes.size());
  if (state_ == State::kEpilogue) return absl::OkStatus();
  buffer_.append(bytes);
  bool progressed = true;
  while (progressed && state_ != State::kEpilogue) {
    progressed = false;
    RETURN_IF_ERROR(Step(&progressed));
  }
  // Drop what is handled, keeping the unhandled tail.
  if (consumed_ > 0) {
    buffer_.erase(0, consumed_);
    consumed_ = 0;
  }
  if (state_ == State::kEpilogue) buffer_.clear();
  return absl::OkStatus();
}

Status MultipartParser::StepPreamble(std::string_view rest, bool* progressed) {
  const size_t at = rest.find(delimiter_);
  if (at == std::string_view::npos) {
    if (total_bytes_ > static_cast<int64_t>(kMaxPreambleBytes)) {
      return absl::InvalidArgumentError(
          StrCat("multipart: no boundary in the first ", kMaxPreambleBytes, " bytes"));
    }
    // Keep only what may still begin a delimiter.
    if (rest.size() >= delimiter_.size()) consumed_ += rest.size() - (delimiter_.size() - 1);
    return absl::OkStatus();
  }
  consumed_ += at + delimiter_.size();
  state_ = State::kAfterDelimiter;
  *progressed = true;
  return absl::OkStatus();
}

Status MultipartParser::StepAfterDelimiter(std::string_view rest, bool* progressed) {
  if (rest.size() < 2) return absl::OkStatus();
  if (rest.substr(0, 2) == "--") {
    state_ = State::kEpilogue;
    *progressed = true;
    return absl::OkStatus();
  }
  // Transport padding (spaces, tabs), then CRLF.
  size_t i = 0;
  while (i < rest.size() && (rest[i] == ' ' || rest[i] == '\t')) ++i;
  if (i + 2 > rest.size()) {
    if (i > 256) return absl::InvalidArgumentError("multipart: junk after a boundary");
    return absl::OkStatus();
  }
  if (rest.substr(i, 2) != "\r\n") {
    return absl::InvalidArgumentError(
        StrCat("multipart: part ", parts_ + 1, ": the boundary is not followed by a line end"));
  }
  consumed_ += i + 2;
  state_ = State::kHeaders;
  *progressed = true;
  return absl::OkStatus();
}

Status MultipartParser::StepHeaders(std::string_view rest, bool* progressed) {
  // No headers at all: the blank line comes first.
  size_t end = rest.starts_with("\r\n") ? 0 : rest.find("\r\n\r\n");
  if (end == std::string_view::npos) {
    if (rest.size() > kMaxHeaderBytes) {
      return absl::InvalidArgumentError(
          StrCat("multipart: part ", parts_ + 1, ": headers over ", kMaxHeaderBytes, " bytes"));
    }
    return absl::OkStatus();
  }
  ++parts_;
  RETURN_IF_ERROR(ParseHeaders(rest.substr(0, end)));
  consumed_ += end == 0 ? 2 : end + 4;
  state_ = State::kBody;
  *progressed = true;
  return absl::OkStatus();
}

Status MultipartParser::StepBody(std::string_view rest, bool* progressed) {
  const size_t at = rest.find(delimiter_);
  if (at == std::string_view::npos) {
    // Everything but what may begin a delimiter goes out now.
    if (rest.size() >= delimiter_.size()) {
      const size_t out = rest.size() - (delimiter_.size() - 1);
      RETURN_IF_ERROR(callbacks_.part_data(rest.substr(0, out)));
      consumed_ += out;
    }
    return absl::OkStatus();
  }
  if (at > 0) RETURN_IF_ERROR(callbacks_.part_data(rest.substr(0, at)));
  if (callbacks_.part_end) RETURN_IF_ERROR(callbacks_.part_end());
  consumed_ += at + delimiter_.size();
  state_ = State::kAfterDelimiter;
  *progressed = true;
  return absl::OkStatus();
}

Status MultipartParser::Step(bool* progressed) {
  const std::string_view rest = std::string_view(buffer_).substr(consumed_);
  switch (state_) {
    case State::kPreamble:
      return StepPreamble(rest, progressed);
    case State::kAfterDelimiter:
      return StepAfterDelimiter(rest, progressed);
    case State::kHeaders:
      return StepHeaders(rest, progressed);
    case State::kBody:
      return StepBody(rest, progressed);
    case State::kEpilogue:
      return absl::OkStatus();
  }
  return absl::OkStatus();
}

Status MultipartParser::ParseHeaders(std::string_view block) {
  Headers headers;
  while (!block.empty()) {
    const size_t eol = block.find("\r\n");
    const std::string_view line = block.substr(0, eol);
    block = eol == std::string_view::npos ? std::string_view() : block.substr(eol + 2);
    if (line.empty()) continue;
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos || colon == 0) {
      return absl::InvalidArgumentError(
          StrCat("multipart: part ", parts_, ": a header line without a name and ':'"));
    }
    headers[Lower(Trim(line.substr(0, colon)))] = std::string(Trim(line.substr(colon + 1)));
  }
  if (callbacks_.part_begin) return callbacks_.part_begin(headers);
  return absl::OkStatus();
}

Status MultipartParser::Finish() {
  switch (state_) {
    case State::kEpilogue:
      return absl::OkStatus();
    case State::kPreamble:
      return absl::InvalidArgumentError(
          StrCat("multipart: the body (", total_bytes_, " bytes) holds no boundary"));
    case State::kAfterDelimiter:
      if (parts_ == 0 && buffer_.size() - consumed_ == 0) {
        return absl::InvalidArgumentError("multipart: the body ends after its first boundary");
      }
      return absl::InvalidArgumentError(StrCat("multipart: truncated: the body ends after part ",
                                               parts_, " without the closing boundary"));
    case State::kHeaders:
      return absl::InvalidArgumentError(
          StrCat("multipart: truncated in the headers of part ", parts_ + 1));
    case State::kBody:
      return absl::InvalidArgumentError(StrCat("multipart: truncated: part ", parts_,
                                               " ends without a boundary after ", total_bytes_,
                                               " bytes"));
  }
  return absl::OkStatus();
}

}  // namespace vpm::pacs

// A streaming parser of multipart/related bodies (RFC 2046), as WADO-RS
// answers a series: parts are split on the boundary alone, so a part's own
// Content-Length (absent, or wrong, on some servers) is never trusted, and
// no part is held whole: its bytes go to the caller as they arrive.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::pacs {

// The boundary parameter of a multipart Content-Type header, quoted or not:
//   multipart/related; type="application/dicom"; boundary=abc
//   Multipart/Related; boundary="a b:c"; type=application/dicom
// InvalidArgument when the type is not multipart/*, or the boundary is
// missing, empty or over 200 bytes.
Result<std::string> MultipartBoundary(std::string_view content_type);

class MultipartParser {
 public:
  // Part headers with lower-case names ("content-type").
  using Headers = std::map<std::string, std::string>;
  struct Callbacks {
    std::function<Status(const Headers&)> part_begin;   // optional
    std::function<Status(std::string_view)> part_data;  // required; any chunking
    std::function<Status()> part_end;                   // optional
  };
  // Limits against a stream that never delimits anything.
  static constexpr size_t kMaxPreambleBytes = size_t{1} << 20;
  static constexpr size_t kMaxHeaderBytes = 16 << 10;

  MultipartParser(std::string boundary, Callbacks callbacks);

  // Feeds the next bytes of the body. A callback's error is returned as is;
  // malformed input is InvalidArgument ("multipart: ...").
  Status Feed(std::string_view bytes);
  // The body ended: InvalidArgument unless the closing delimiter
  // ("--BOUNDARY--") was seen, naming where the body was cut.
  Status Finish();
  int64_t parts() const { return parts_; }  // parts begun

 private:
  enum class State { kPreamble, kAfterDelimiter, kHeaders, kBody, kEpilogue };
  Status Step(bool* progressed);
  // One state's step on the unhandled bytes `rest`; *progressed when it
  // moved to another state.
  Status StepPreamble(std::string_view rest, bool* progressed);
  Status StepAfterDelimiter(std::string_view rest, bool* progressed);
  Status StepHeaders(std::string_view rest, bool* progressed);
  Status StepBody(std::string_view rest, bool* progressed);
  Status ParseHeaders(std::string_view block);

  const std::string delimiter_;  // "\r\n--" + boundary
  Callbacks callbacks_;
  State state_ = State::kPreamble;
  std::string buffer_;
  size_t consumed_ = 0;  // bytes of buffer_ already handled
  int64_t parts_ = 0;
  int64_t total_bytes_ = 0;
};

}  // namespace vpm::pacs

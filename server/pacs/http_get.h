// One HTTP GET (or POST) through libcurl, the answer's body streamed to the
// caller: how the DICOMweb client talks to a PACS. Credentials go to libcurl only (never
// into a URL, a log or an error); redirects are not followed (they could
// carry the credentials elsewhere); only http and https are spoken.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/status.h"

namespace vpm::pacs {

struct HttpRequest {
  std::string url;                   // with its query
  std::vector<std::string> headers;  // "Accept: ..."
  std::string username;              // basic auth when set
  std::string password;              // secret
  std::string bearer_token;          // secret; "Authorization: Bearer" when set
  std::string ca_file;               // PEM bundle; empty: the system's
  std::string label;                 // what errors call the server: "PACS 'orthanc'"
  int64_t connect_timeout_s = 10;
  // A transfer slower than 1 byte/s for this long is DeadlineExceeded.
  int64_t stall_timeout_s = 60;
};

struct HttpResponse {
  int64_t status = 0;           // 200, 404, ...
  std::string content_type;     // of the final response
  int64_t content_length = -1;  // -1: not given
};

// Receives the body of a 2xx answer, chunk by chunk, after its headers.
using HttpBodySink = std::function<Status(const HttpResponse& head, std::string_view chunk)>;

// GETs `request.url`. The body of a 2xx answer goes to `sink`; any other
// status's body is read and dropped. Returns the response head (the caller
// maps statuses). Errors: Unavailable (cannot connect or resolve, TLS
// failures, the connection cut), DeadlineExceeded (connect timeout or a
// stalled transfer), the sink's error, or `cancel`'s status (polled
// during the transfer). Messages name `label` and the URL without its query
// (a search's query holds patient identifiers).
Result<HttpResponse> HttpGet(const HttpRequest& request, const HttpBodySink& sink,
                             const CancelToken& cancel = {});

// POSTs `body` (its Content-Type among request.headers) to `request.url`;
// the answer as HttpGet's.
Result<HttpResponse> HttpPost(const HttpRequest& request, const std::string& body,
                              const HttpBodySink& sink, const CancelToken& cancel = {});

}  // namespace vpm::pacs

#include "server/pacs/http_get.h"

#include <curl/curl.h>

#include <cctype>
#include <memory>
#include <mutex>

namespace vpm::pacs {
namespace {

void GlobalInit() {
  static std::once_flag once;
  std::call_once(once, [] { curl_global_init(CURL_GLOBAL_DEFAULT); });
}

struct Transfer {
  CURL* curl = nullptr;
  const HttpBodySink* sink = nullptr;
  const CancelToken* cancel = nullptr;
  HttpResponse head;
  bool head_filled = false;
  std::string content_type_seen;  // of the response being received
  Status error;                   // a sink's or the token's, when it aborted
};

std::string LowerAscii(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

size_t OnHeader(char* data, size_t size, size_t count, void* user) {
  auto* t = static_cast<Transfer*>(user);
  const std::string_view line(data, size * count);
  if (line.starts_with("HTTP/")) t->content_type_seen.clear();  // a new response (100, 401...)
  const size_t colon = line.find(':');
  if (colon != std::string_view::npos && LowerAscii(line.substr(0, colon)) == "content-type") {
    std::string_view value = line.substr(colon + 1);
    while (!value.empty() && (value.front() == ' ' || value.front() == '\t'))
      value.remove_prefix(1);
    while (!value.empty() &&
           (value.back() == '\r' || value.back() == '\n' || value.back() == ' ')) {
      value.remove_suffix(1);
    }
    t->content_type_seen = std::string(value);
  }
  return size * count;
}

void FillHead(Transfer* t) {
  if (t->head_filled) return;
  t->head_filled = true;
  long code = 0;
  curl_easy_getinfo(t->curl, CURLINFO_RESPONSE_CODE, &code);
  t->head.status = code;
  t->head.content_type = t->content_type_seen;
  curl_off_t length = -1;
  curl_easy_getinfo(t->curl, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &length);
  t->head.content_length = length;
}

size_t OnBody(char* data, size_t size, size_t count, void* user) {
  auto* t = static_cast<Transfer*>(user);
  FillHead(t);
  if (t->head.status < 200 || t->head.status > 299) return size * count;  // dropped
  Status status = (*t->sink)(t->head, std::string_view(data, size * count));
  if (!status.ok()) {
    t->error = std::move(status);
    return CURL_WRITEFUNC_ERROR;
  }
  return size * count;
}

int OnProgress(void* user, curl_off_t, curl_off_t, curl_off_t, curl_off_t) {
  auto* t = static_cast<Transfer*>(user);
  Status status = t->cancel->Check();
  if (status.ok()) return 0;
  t->error = std::move(status);
  return 1;
}

struct CurlDeleter {
  void operator()(CURL* c) const { curl_easy_cleanup(c); }
};
struct SlistDeleter {
  void operator()(curl_slist* l) const { curl_slist_free_all(l); }
};

}  // namespace

namespace {

// GET, or POST of `body` when it is not null.
Result<HttpResponse> Perform(const HttpRequest& request, const std::string* body,
                             const HttpBodySink& sink, const CancelToken& cancel) {
  GlobalInit();
  std::unique_ptr<CURL, CurlDeleter> curl(curl_easy_init());
  if (!curl) return absl::InternalError("libcurl: cannot make a handle");
  const std::string where = request.url.substr(0, request.url.find('?'));
  Transfer t;
  t.curl = curl.get();
  t.sink = &sink;
  t.cancel = &cancel;
  curl_slist* list = nullptr;
  for (const std::string& h : request.headers) list = curl_slist_append(list, h.c_str());
  std::string bearer;
  if (!request.bearer_token.empty()) {
    bearer = "Authorization: Bearer " + request.bearer_token;
    list = curl_slist_append(list, bearer.c_str());
  }
  std::unique_ptr<curl_slist, SlistDeleter> headers(list);
  CURL* c = curl.get();
  curl_easy_setopt(c, CURLOPT_URL, request.url.c_str());
  curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, "http,https");
  curl_easy_setopt(c, CURLOPT_FOLLOWLOCATION, 0L);
  curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(c, CURLOPT_HTTPHEADER, headers.get());
  curl_easy_setopt(c, CURLOPT_CONNECTTIMEOUT, static_cast<long>(request.connect_timeout_s));
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_LIMIT, 1L);
  curl_easy_setopt(c, CURLOPT_LOW_SPEED_TIME, static_cast<long>(request.stall_timeout_s));
  if (!request.username.empty()) {
    curl_easy_setopt(c, CURLOPT_HTTPAUTH, CURLAUTH_BASIC);
    curl_easy_setopt(c, CURLOPT_USERNAME, request.username.c_str());
    curl_easy_setopt(c, CURLOPT_PASSWORD, request.password.c_str());
  }
  if (!request.ca_file.empty()) curl_easy_setopt(c, CURLOPT_CAINFO, request.ca_file.c_str());
  if (body != nullptr) {
    curl_easy_setopt(c, CURLOPT_POST, 1L);
    curl_easy_setopt(c, CURLOPT_POSTFIELDS, body->data());
    curl_easy_setopt(c, CURLOPT_POSTFIELDSIZE_LARGE, static_cast<curl_off_t>(body->size()));
  }
  curl_easy_setopt(c, CURLOPT_HEADERFUNCTION, OnHeader);
  curl_easy_setopt(c, CURLOPT_HEADERDATA, &t);
  curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, OnBody);
  curl_easy_setopt(c, CURLOPT_WRITEDATA, &t);
  curl_easy_setopt(c, CURLOPT_NOPROGRESS, 0L);
  curl_easy_setopt(c, CURLOPT_XFERINFOFUNCTION, OnProgress);
  curl_easy_setopt(c, CURLOPT_XFERINFODATA, &t);
  const CURLcode code = curl_easy_perform(c);
  if (!t.error.ok()) return t.error;
  if (code != CURLE_OK) {
    const std::string what = StrCat(request.label, ": ", where, ": ", curl_easy_strerror(code));
    switch (code) {
      case CURLE_OPERATION_TIMEDOUT:
        return absl::DeadlineExceededError(StrCat(what, " (no answer in time)"));
      case CURLE_SSL_CACERT_BADFILE:
      case CURLE_PEER_FAILED_VERIFICATION:
      case CURLE_SSL_CONNECT_ERROR:
        return absl::UnavailableError(StrCat(what, " (TLS: check the endpoint's ca_file)"));
      default:
        return absl::UnavailableError(StrCat(what, " (is the PACS running and reachable?)"));
    }
  }
  FillHead(&t);
  return t.head;
}

}  // namespace

Result<HttpResponse> HttpGet(const HttpRequest& request, const HttpBodySink& sink,
                             const CancelToken& cancel) {
  return Perform(request, nullptr, sink, cancel);
}

Result<HttpResponse> HttpPost(const HttpRequest& request, const std::string& body,
                              const HttpBodySink& sink, const CancelToken& cancel) {
  return Perform(request, &body, sink, cancel);
}

}  // namespace vpm::pacs

#include "server/pacs/stow_client.h"

#include <nlohmann/json.hpp>

#include "server/common/random_hex.h"
#include "server/pacs/dicomweb_client.h"
#include "server/pacs/http_get.h"

namespace vpm::pacs {
namespace {

using nlohmann::json;

constexpr int64_t kMaxStowAnswerBytes = int64_t{4} << 20;


// One multipart/related body of files [begin, end).
std::string StowBody(const std::vector<const std::string*>& files, size_t begin, size_t end,
                 const std::string& boundary) {
  std::string body;
  for (size_t n = begin; n < end; ++n) {
    body += StrCat("--", boundary, "\r\nContent-Type: application/dicom\r\n\r\n");
    body += *files[n];
    body += "\r\n";
  }
  body += StrCat("--", boundary, "--\r\n");
  return body;
}

// POSTs one batch; its answer counts.
Result<StowAnswer> PostBatch(const PacsEndpoint& endpoint, const std::string& body,
                             const std::string& boundary, const StowOptions& options,
                             const CancelToken& cancel) {
  const HttpRequest request = RequestTo(
      endpoint, endpoint.dicomweb_url + "/studies",
      {StrCat("Content-Type: multipart/related; type=\"application/dicom\"; boundary=", boundary),
       "Accept: application/dicom+json"},
      options.connect_timeout_s, options.stall_timeout_s);
  std::string answer;
  ASSIGN_OR_RETURN(const HttpResponse head,
                   HttpPost(
                       request, body,
                       [&](const HttpResponse&, std::string_view chunk) -> Status {
                         if (int64_t(answer.size() + chunk.size()) > kMaxStowAnswerBytes) {
                           return absl::ResourceExhaustedError(StrCat(
                               EndpointLabel(endpoint), ": a STOW-RS answer over ", kMaxStowAnswerBytes,
                               " bytes"));
                         }
                         answer.append(chunk);
                         return absl::OkStatus();
                       },
                       cancel));
  if (head.status == 409 || head.status == 202) {
    StowAnswer counted = ParseStowAnswer(answer).value_or(StowAnswer{});
    if (counted.failed == 0) counted.failed = 1;
    return counted;
  }
  if (head.status < 200 || head.status > 299) {
    return StatusFromHttp(head.status, EndpointLabel(endpoint), "STOW-RS /studies");
  }
  Result<StowAnswer> counted = ParseStowAnswer(answer);
  if (!counted.ok()) {
    return absl::UnavailableError(
        StrCat(EndpointLabel(endpoint), ": STOW-RS answer: ", counted.status().message()));
  }
  return counted;
}

}  // namespace

Result<StowAnswer> ParseStowAnswer(const std::string& body) {
  const json doc = json::parse(body, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) {
    return absl::InvalidArgumentError("not a DICOM JSON object");
  }
  StowAnswer out;
  const auto items = [&](const char* tag) -> const json* {
    auto it = doc.find(tag);
    if (it == doc.end() || !it->is_object()) return nullptr;
    auto value = it->find("Value");
    return value != it->end() && value->is_array() ? &*value : nullptr;
  };
  if (const json* referenced = items("00081199")) out.referenced = int64_t(referenced->size());
  if (const json* failed = items("00081198")) {
    out.failed = int64_t(failed->size());
    if (!failed->empty() && (*failed)[0].is_object()) {
      auto reason = (*failed)[0].find("00081197");
      if (reason != (*failed)[0].end() && reason->contains("Value")) {
        out.first_failure = (*reason)["Value"].dump();
      }
    }
  }
  return out;
}

Result<StowResult> StoreInstances(const PacsEndpoint& endpoint,
                                  const std::vector<const std::string*>& files,
                                  const StowOptions& options, const ProgressFn& progress,
                                  const CancelToken& cancel) {
  int64_t total_bytes = 0;
  for (const std::string* f : files) total_bytes += int64_t(f->size());
  const std::string boundary = StrCat("vpm-stow-", RandomHex(16));
  StowResult result;
  int64_t sent_bytes = 0, refused = 0;
  std::string first_failure;
  for (size_t begin = 0; begin < files.size();) {
    RETURN_IF_ERROR(cancel.Check());
    size_t end = begin;
    int64_t batch = 0;
    while (end < files.size() && (end == begin || batch + int64_t(files[end]->size()) <=
                                                      options.batch_bytes)) {
      batch += int64_t(files[end++]->size());
    }
    ASSIGN_OR_RETURN(const StowAnswer answer,
                     PostBatch(endpoint, StowBody(files, begin, end, boundary), boundary, options,
                               cancel));
    ++result.requests;
    const int64_t sent = int64_t(end - begin);
    result.stored += std::min(answer.referenced, sent);
    refused += std::max(answer.failed, sent - std::min(answer.referenced, sent));
    if (first_failure.empty()) first_failure = answer.first_failure;
    sent_bytes += batch;
    if (progress) progress(double(sent_bytes) / double(std::max<int64_t>(total_bytes, 1)), "sending");
    begin = end;
  }
  if (refused > 0) {
    return absl::FailedPreconditionError(
        StrCat(EndpointLabel(endpoint), ": the PACS refused ", refused, " of ", files.size(),
               " instances", first_failure.empty() ? "" : StrCat(" (failure reason ", first_failure, ")")));
  }
  return result;
}

}  // namespace vpm::pacs

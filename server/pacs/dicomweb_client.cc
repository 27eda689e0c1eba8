#include "server/pacs/dicomweb_client.h"

#include <algorithm>
#include <memory>
#include <set>

#include "server/pacs/dicom_part_writer.h"
#include "server/pacs/http_get.h"
#include "server/pacs/multipart_parser.h"
#include "server/pacs/stow_client.h"

namespace vpm::pacs {
namespace {

constexpr const char* kAcceptDicom =
    "Accept: multipart/related; type=\"application/dicom\"; transfer-syntax=*";

}  // namespace

Status StatusFromHttp(int64_t status, const std::string& label, const std::string& what) {
  const std::string head = StrCat(label, ": ", what, ": HTTP ", status);
  switch (status) {
    case 400:
      return absl::InvalidArgumentError(StrCat(head, " (the PACS found the request malformed)"));
    case 401:
      return absl::PermissionDeniedError(
          StrCat(head,
                 " (the PACS refused vpm's credentials: check the endpoint's username "
                 "and password_file or bearer_token_file)"));
    case 403:
      return absl::PermissionDeniedError(StrCat(head, " (the PACS forbids this to vpm's account)"));
    case 404:
      return absl::NotFoundError(StrCat(head,
                                        " (no such study or series on the PACS, or no "
                                        "DICOMweb at the endpoint's URL)"));
    default:
      break;
  }
  if (status == 408 || status == 429 || status >= 500) {
    return absl::UnavailableError(StrCat(head, " (the PACS failed; try again later)"));
  }
  return absl::UnavailableError(StrCat(head, " (an answer vpm does not expect)"));
}

HttpRequest RequestTo(const PacsEndpoint& endpoint, std::string url,
                      std::vector<std::string> headers, int64_t connect_timeout_s,
                      int64_t stall_timeout_s) {
  return {.url = std::move(url),
          .headers = std::move(headers),
          .username = endpoint.username,
          .password = endpoint.password,
          .bearer_token = endpoint.bearer_token,
          .ca_file = endpoint.ca_file,
          .label = EndpointLabel(endpoint),
          .connect_timeout_s = connect_timeout_s,
          .stall_timeout_s = stall_timeout_s};
}

DicomwebClient::DicomwebClient(PacsEndpoint endpoint, Options options)
    : endpoint_(std::move(endpoint)), options_(options) {}

Result<std::string> DicomwebClient::GetText(const std::string& path_and_query,
                                            const CancelToken& cancel) const {
  const HttpRequest request =
      RequestTo(endpoint_, endpoint_.dicomweb_url + path_and_query,
                {"Accept: application/dicom+json"}, options_.connect_timeout_s,
                options_.stall_timeout_s);
  std::string body;
  const int64_t cap = options_.max_answer_bytes;
  ASSIGN_OR_RETURN(const HttpResponse head,
                   HttpGet(
                       request,
                       [&](const HttpResponse&, std::string_view chunk) -> Status {
                         if (static_cast<int64_t>(body.size() + chunk.size()) > cap) {
                           return absl::ResourceExhaustedError(
                               StrCat(EndpointLabel(endpoint_), ": a QIDO answer over ", cap, " bytes"));
                         }
                         body.append(chunk);
                         return absl::OkStatus();
                       },
                       cancel));
  if (head.status == 204) return std::string();
  if (head.status < 200 || head.status > 299) {
    const std::string what = path_and_query.substr(0, path_and_query.find('?'));
    return StatusFromHttp(head.status, EndpointLabel(endpoint_), StrCat("GET ", what));
  }
  return body;
}

Result<StudySearch> DicomwebClient::SearchStudies(const StudyQuery& query,
                                                  const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckStudyQuery(query));
  StudySearch out;
  std::set<std::string> seen;
  int64_t offset = 0;
  const int64_t page = std::max<int64_t>(1, endpoint_.page_size);
  while (static_cast<int64_t>(out.studies.size()) < query.limit) {
    const int64_t want = std::min(page, query.limit - static_cast<int64_t>(out.studies.size()));
    ++out.requests;
    ASSIGN_OR_RETURN(const std::string body,
                     GetText(StrCat("/studies?", StudyQueryString(query, want, offset)), cancel));
    Result<std::vector<StudySummary>> studies = ParseStudies(body);
    if (!studies.ok()) {
      return absl::UnavailableError(
          StrCat(EndpointLabel(endpoint_), ": study search: ", studies.status().message()));
    }
    int64_t fresh = 0;
    for (StudySummary& s : *studies) {
      if (!seen.insert(s.study_uid).second) continue;
      ++fresh;
      if (static_cast<int64_t>(out.studies.size()) == query.limit) {
        out.truncated = true;
        break;
      }
      out.studies.push_back(std::move(s));
    }
    offset += static_cast<int64_t>(studies->size());
    // A short page is the last; a page with nothing new means the server
    // ignored `offset` (or limits on its own): what it has is all there is.
    if (static_cast<int64_t>(studies->size()) < want) break;
    if (fresh == 0) {
      out.truncated = true;  // more may match, out of reach of this server's paging
      break;
    }
    if (static_cast<int64_t>(out.studies.size()) == query.limit) {
      out.truncated = true;
      break;
    }
  }
  return out;
}

Result<std::vector<SeriesSummary>> DicomwebClient::ListSeries(const std::string& study_uid,
                                                              const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  ASSIGN_OR_RETURN(const std::string body,
                   GetText(StrCat("/studies/", study_uid,
                                  "/series?includefield=0008103E&includefield=00180015"
                                  "&includefield=00201209&includefield=00200011"),
                           cancel));
  Result<std::vector<SeriesSummary>> series = ParseSeries(body);
  if (!series.ok()) {
    return absl::UnavailableError(
        StrCat(EndpointLabel(endpoint_), ": series listing: ", series.status().message()));
  }
  std::stable_sort(series->begin(), series->end(),
                   [](const SeriesSummary& a, const SeriesSummary& b) {
                     return a.series_number < b.series_number;
                   });
  return *std::move(series);
}

Result<RetrievedSeries> DicomwebClient::RetrieveSeries(
    const std::string& study_uid, const std::string& series_uid,
    const std::filesystem::path& folder, int64_t max_bytes, int64_t expected_instances,
    const ProgressFn& progress, const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  return RetrieveParts(StrCat("/studies/", study_uid, "/series/", series_uid),
                       StrCat("series ", series_uid), folder, max_bytes, expected_instances,
                       progress, cancel);
}

Result<RetrievedSeries> DicomwebClient::RetrieveInstance(const std::string& study_uid,
                                                         const std::string& series_uid,
                                                         const std::filesystem::path& folder,
                                                         int64_t max_bytes,
                                                         const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  const std::string series_path = StrCat("/studies/", study_uid, "/series/", series_uid);
  ASSIGN_OR_RETURN(const std::string body,
                   GetText(StrCat(series_path, "/instances?includefield=00200013"), cancel));
  Result<std::vector<InstanceSummary>> instances = ParseInstances(body);
  if (!instances.ok()) {
    return absl::UnavailableError(
        StrCat(EndpointLabel(endpoint_), ": instance listing: ", instances.status().message()));
  }
  const InstanceSummary* middle = MiddleInstance(*instances);
  if (middle == nullptr) {
    return absl::NotFoundError(
        StrCat(EndpointLabel(endpoint_), ": series ", series_uid, ": the PACS lists no instance"));
  }
  return RetrieveParts(StrCat(series_path, "/instances/", middle->sop_uid),
                       StrCat("series ", series_uid, " instance ", middle->sop_uid), folder,
                       max_bytes, 1, nullptr, cancel);
}

Result<RetrievedSeries> DicomwebClient::RetrieveParts(
    const std::string& path, const std::string& what_part, const std::filesystem::path& folder,
    int64_t max_bytes, int64_t expected_instances, const ProgressFn& progress,
    const CancelToken& cancel) const {
  const std::string label = EndpointLabel(endpoint_);
  const std::string what = StrCat(label, ": ", what_part);
  const HttpRequest request =
      RequestTo(endpoint_, StrCat(endpoint_.dicomweb_url, path), {kAcceptDicom},
                options_.connect_timeout_s, options_.stall_timeout_s);
  DicomPartWriter writer(folder, what, max_bytes);
  std::unique_ptr<MultipartParser> parser;
  int64_t received = 0;
  const auto on_body = [&](const HttpResponse& h, std::string_view chunk) -> Status {
    if (!parser) {  // the boundary comes with the answer's headers
      Result<std::string> boundary = MultipartBoundary(h.content_type);
      if (!boundary.ok()) {
        return absl::InvalidArgumentError(StrCat(what, ": ", boundary.status().message()));
      }
      parser = std::make_unique<MultipartParser>(*boundary, writer.Callbacks());
    }
    received += static_cast<int64_t>(chunk.size());
    Status fed = parser->Feed(chunk);
    if (!fed.ok() && absl::IsInvalidArgument(fed) &&
        std::string_view(fed.message().data(), fed.message().size()).starts_with("multipart:")) {
      return absl::InvalidArgumentError(StrCat(what, ": ", fed.message()));
    }
    RETURN_IF_ERROR(fed);
    if (progress) {
      double f = 0;
      if (expected_instances > 0) {
        f = static_cast<double>(writer.files()) / static_cast<double>(expected_instances);
      } else if (h.content_length > 0) {
        f = static_cast<double>(received) / static_cast<double>(h.content_length);
      }
      progress(std::min(f, 0.99), "retrieving");
    }
    return absl::OkStatus();
  };
  ASSIGN_OR_RETURN(const HttpResponse head, HttpGet(request, on_body, cancel));
  if (head.status < 200 || head.status > 299) {
    return StatusFromHttp(head.status, label, StrCat("retrieve ", what_part));
  }
  if (parser) {
    if (Status done = parser->Finish(); !done.ok()) {
      return absl::InvalidArgumentError(StrCat(what, ": ", done.message()));
    }
  }
  if (writer.files() == 0) return absl::NotFoundError(StrCat(what, ": the PACS sent no instances"));
  if (progress) progress(1.0, "retrieving");
  return RetrievedSeries{.instances = writer.files(), .bytes = writer.bytes()};
}

Status DicomwebClient::Store(const std::vector<const std::string*>& files,
                             const ProgressFn& progress, const CancelToken& cancel) const {
  StowOptions stow;
  stow.connect_timeout_s = options_.connect_timeout_s;
  stow.stall_timeout_s = options_.stall_timeout_s;
  return StoreInstances(endpoint_, files, stow, progress, cancel).status();
}

}  // namespace vpm::pacs

// A DICOMweb client of one PACS endpoint: QIDO-RS study search and series
// listing, WADO-RS retrieval of one series into a folder.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/pacs/dicom_json.h"
#include "server/pacs/http_get.h"
#include "server/pacs/pacs_client.h"
#include "server/pacs/pacs_endpoint.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {

class DicomwebClient : public PacsClient {
 public:
  struct Options {
    int64_t max_answer_bytes = int64_t{16} << 20;  // one QIDO answer
    int64_t connect_timeout_s = 10;
    int64_t stall_timeout_s = 60;
  };
  DicomwebClient(PacsEndpoint endpoint, Options options);

  // QIDO-RS /studies, page by page (endpoint.page_size, limit and offset)
  // until query.limit studies, a short page, or a page with nothing new: a
  // server that ignores `offset` answers the first page again, and the
  // search ends there instead of looping, marked truncated. Errors: CheckStudyQuery's, and those of
  // Get below.
  Result<StudySearch> SearchStudies(const StudyQuery& query,
                                    const CancelToken& cancel) const override;

  // QIDO-RS /studies/UID/series, sorted by SeriesNumber.
  Result<std::vector<SeriesSummary>> ListSeries(const std::string& study_uid,
                                                const CancelToken& cancel) const override;

  // WADO-RS /studies/UID/series/UID with
  // Accept: multipart/related; type="application/dicom"; transfer-syntax=*
  // (the stored transfer syntax: no transcoding on the PACS), each part
  // written to `folder` (which must exist) as 000001.dcm, 000002.dcm, ... as
  // it streams in. `expected_instances` (> 0) paces `progress`. Errors:
  // InvalidArgument for a malformed or truncated multipart body, a part
  // that is not DICOM Part 10 or of another content type, no parts;
  // ResourceExhausted past `max_bytes`; Internal when a file cannot be
  // written; the HTTP and transfer errors of Get. Files written before an
  // error stay: the caller owns the folder.
  Result<RetrievedSeries> RetrieveSeries(const std::string& study_uid,
                                         const std::string& series_uid,
                                         const std::filesystem::path& folder, int64_t max_bytes,
                                         int64_t expected_instances, const ProgressFn& progress,
                                         const CancelToken& cancel) const override;

  // QIDO-RS /studies/UID/series/UID/instances (SOPInstanceUID and
  // InstanceNumber), then WADO-RS of the middle instance
  // (/instances/UID, transfer-syntax=*) into `folder` as 000001.dcm.
  // NotFound when the PACS lists no instance; else as RetrieveSeries.
  Result<RetrievedSeries> RetrieveInstance(const std::string& study_uid,
                                           const std::string& series_uid,
                                           const std::filesystem::path& folder, int64_t max_bytes,
                                           const CancelToken& cancel) const override;

  // STOW-RS (stow_client.h).
  Status Store(const std::vector<const std::string*>& files, const ProgressFn& progress,
               const CancelToken& cancel) const override;

  const PacsEndpoint& endpoint() const override { return endpoint_; }

 private:
  // GETs base + `path_and_query` into a string of at most max_answer_bytes.
  // Errors: an HTTP status other than 2xx as StatusFromHttp says, and
  // HttpGet's.
  Result<std::string> GetText(const std::string& path_and_query, const CancelToken& cancel) const;

  // WADO-RS of `path` (a series or an instance, `what` in messages), each
  // part written into `folder`; as RetrieveSeries.
  Result<RetrievedSeries> RetrieveParts(const std::string& path, const std::string& what,
                                        const std::filesystem::path& folder, int64_t max_bytes,
                                        int64_t expected_instances, const ProgressFn& progress,
                                        const CancelToken& cancel) const;

  PacsEndpoint endpoint_;
  Options options_;
};

// The status for an HTTP answer `status` (not 2xx) to `what` ("study
// search") from the PACS `label`: 401 and 403 PermissionDenied (the PACS
// refused vpm's credentials, or the action), 404 NotFound, 400
// InvalidArgument, 408, 429 and 5xx Unavailable; the message says which and
// never quotes the answer's body.
Status StatusFromHttp(int64_t status, const std::string& label, const std::string& what);

// A request to `url` (the endpoint's DICOMweb base and a path) with the
// endpoint's credentials and CA bundle, labelled "PACS 'NAME'" for errors.
HttpRequest RequestTo(const PacsEndpoint& endpoint, std::string url,
                      std::vector<std::string> headers, int64_t connect_timeout_s,
                      int64_t stall_timeout_s);

}  // namespace vpm::pacs

// What the PACS gateway asks of one endpoint, whatever it speaks: DICOMweb
// (dicomweb_client.h) or DICOM networking (dimse_client.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/pacs/dicom_json.h"
#include "server/pacs/pacs_endpoint.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {

struct StudySearch {
  std::vector<StudySummary> studies;  // in the PACS's order, each UID once
  bool truncated = false;             // the limit was reached; more may match
  int64_t requests = 0;               // QIDO pages or C-FIND requests made
};

struct RetrievedSeries {
  int64_t instances = 0;  // files written
  int64_t bytes = 0;      // their total size
};

class PacsClient {
 public:
  virtual ~PacsClient() = default;
  virtual Result<StudySearch> SearchStudies(const StudyQuery& query,
                                            const CancelToken& cancel) const = 0;
  // Sorted by SeriesNumber.
  virtual Result<std::vector<SeriesSummary>> ListSeries(const std::string& study_uid,
                                                        const CancelToken& cancel) const = 0;
  // The series' instances written into `folder` (existing) as they arrive,
  // at most `max_bytes` of them (ResourceExhausted past it); files written
  // before an error stay (the caller owns the folder).
  virtual Result<RetrievedSeries> RetrieveSeries(const std::string& study_uid,
                                                 const std::string& series_uid,
                                                 const std::filesystem::path& folder,
                                                 int64_t max_bytes, int64_t expected_instances,
                                                 const ProgressFn& progress,
                                                 const CancelToken& cancel) const = 0;
  // One instance of the series, the one a thumbnail shows (the middle one
  // by InstanceNumber when the PACS lists them), written into `folder`
  // (existing), at most `max_bytes` (ResourceExhausted past it). Errors as
  // RetrieveSeries.
  virtual Result<RetrievedSeries> RetrieveInstance(const std::string& study_uid,
                                                   const std::string& series_uid,
                                                   const std::filesystem::path& folder,
                                                   int64_t max_bytes,
                                                   const CancelToken& cancel) const = 0;
  // Sends whole Part 10 files; every one must be stored (FailedPrecondition
  // "the PACS refused N of M instances" otherwise).
  virtual Status Store(const std::vector<const std::string*>& files, const ProgressFn& progress,
                       const CancelToken& cancel) const = 0;
  virtual const PacsEndpoint& endpoint() const = 0;
};

}  // namespace vpm::pacs

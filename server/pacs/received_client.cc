#include "server/pacs/received_client.h"

#include "server/common/prefix_status.h"

namespace vpm::pacs {

Result<StudySearch> ReceivedClient::SearchStudies(const StudyQuery& query,
                                                  const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckStudyQuery(query));
  RETURN_IF_ERROR(cancel.Check());
  return store_->Search(query, endpoint_.receive_from);
}

Result<std::vector<SeriesSummary>> ReceivedClient::ListSeries(const std::string& study_uid,
                                                              const CancelToken& cancel) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(cancel.Check());
  return store_->ListSeries(study_uid, endpoint_.receive_from);
}

Result<RetrievedSeries> ReceivedClient::RetrieveSeries(const std::string&, const std::string&,
                                                       const std::filesystem::path&, int64_t,
                                                       int64_t, const ProgressFn&,
                                                       const CancelToken&) const {
  return absl::FailedPreconditionError(
      StrCat(EndpointLabel(endpoint_), ": received series are read in place"));
}

Result<RetrievedSeries> ReceivedClient::RetrieveInstance(const std::string&, const std::string&,
                                                         const std::filesystem::path&, int64_t,
                                                         const CancelToken&) const {
  return absl::FailedPreconditionError(
      StrCat(EndpointLabel(endpoint_), ": received series are read in place"));
}

Status ReceivedClient::Store(const std::vector<const std::string*>&, const ProgressFn&,
                             const CancelToken&) const {
  return absl::FailedPreconditionError(StrCat(
      EndpointLabel(endpoint_),
      " holds what DICOM nodes sent to vpm; export to the PACS the study came from"));
}

Result<std::shared_ptr<ReceivedStore::Lease>> ReceivedClient::OpenSeries(
    const std::string& study_uid, const std::string& series_uid) const {
  RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  Result<std::shared_ptr<ReceivedStore::Lease>> lease =
      store_->OpenSeries(study_uid, series_uid, endpoint_.receive_from);
  if (!lease.ok()) return PrefixStatus(lease.status(), EndpointLabel(endpoint_));
  return lease;
}

}  // namespace vpm::pacs

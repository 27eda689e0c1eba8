// A "receive" endpoint: the series DICOM nodes sent to vpm's listener,
// searched and listed from the received store's index. Its series are read
// in place (OpenSeries), not retrieved; it takes no export.
#pragma once

#include <memory>

#include "server/pacs/pacs_client.h"
#include "server/pacs/received_store.h"

namespace vpm::pacs {

class ReceivedClient : public PacsClient {
 public:
  // `store` outlives the client.
  ReceivedClient(PacsEndpoint endpoint, const ReceivedStore* store)
      : endpoint_(std::move(endpoint)), store_(store) {}

  Result<StudySearch> SearchStudies(const StudyQuery& query,
                                    const CancelToken& cancel) const override;
  Result<std::vector<SeriesSummary>> ListSeries(const std::string& study_uid,
                                                const CancelToken& cancel) const override;
  // FailedPrecondition: a received series is read in place (OpenSeries).
  Result<RetrievedSeries> RetrieveSeries(const std::string& study_uid,
                                         const std::string& series_uid,
                                         const std::filesystem::path& folder, int64_t max_bytes,
                                         int64_t expected_instances, const ProgressFn& progress,
                                         const CancelToken& cancel) const override;
  // FailedPrecondition: a received series is read in place (OpenSeries).
  Result<RetrievedSeries> RetrieveInstance(const std::string& study_uid,
                                           const std::string& series_uid,
                                           const std::filesystem::path& folder, int64_t max_bytes,
                                           const CancelToken& cancel) const override;
  // FailedPrecondition: nothing is sent to a receive endpoint.
  Status Store(const std::vector<const std::string*>& files, const ProgressFn& progress,
               const CancelToken& cancel) const override;
  // The received series' folder, held as it is while the lease lives.
  Result<std::shared_ptr<ReceivedStore::Lease>> OpenSeries(const std::string& study_uid,
                                                           const std::string& series_uid) const;

  const PacsEndpoint& endpoint() const override { return endpoint_; }

 private:
  PacsEndpoint endpoint_;
  const ReceivedStore* store_;
};

}  // namespace vpm::pacs

// A PACS endpoint reached by DICOM networking (DIMSE, DCMTK's DcmSCU), for
// archives without DICOMweb: C-FIND (study root) to search studies and list
// a study's series, C-GET to retrieve a series on the same association (no
// port of vpm's own for the PACS to call back), C-STORE to send an export,
// C-ECHO to check the node. Each call is one association, released after.
#pragma once

#include <cstdint>

#include "server/pacs/move_registry.h"
#include "server/pacs/pacs_client.h"

namespace vpm::pacs {

class DimseClient : public PacsClient {
 public:
  struct Options {
    int64_t connect_timeout_s = 10;  // TCP connect and association negotiation
    int64_t dimse_timeout_s = 60;    // between two messages of the PACS
    int64_t max_find_answers = 5000; // C-FIND answers read before cancelling
    double move_arrival_s = 30;      // after a C-MOVE's last answer, for its instances to land
  };
  // `moves`: vpm's listener's registry (dicom_listener.h), required for an
  // endpoint with "retrieve": "move"; it outlives the client.
  DimseClient(PacsEndpoint endpoint, Options options, MoveRegistry* moves = nullptr);

  // C-ECHO. Errors as below.
  Status Echo(const CancelToken& cancel) const;

  // C-FIND at STUDY level, matching as the PACS does (wildcards, date
  // ranges). Answers past query.limit cancel the find; the search is then
  // truncated.
  Result<StudySearch> SearchStudies(const StudyQuery& query,
                                    const CancelToken& cancel) const override;
  Result<std::vector<SeriesSummary>> ListSeries(const std::string& study_uid,
                                                const CancelToken& cancel) const override;
  // C-GET of one series; every instance written as it arrives (its own
  // transfer syntax kept). An instance of another series is InvalidArgument
  // (mixed series); nothing received is NotFound. With "retrieve": "move",
  // C-MOVE to the endpoint's move_destination instead: the instances come
  // through vpm's listener into `folder` (MoveRegistry), and the retrieval
  // ends once the PACS's count of sent instances has arrived.
  Result<RetrievedSeries> RetrieveSeries(const std::string& study_uid,
                                         const std::string& series_uid,
                                         const std::filesystem::path& folder, int64_t max_bytes,
                                         int64_t expected_instances, const ProgressFn& progress,
                                         const CancelToken& cancel) const override;
  // C-FIND at IMAGE level (SOPInstanceUID, InstanceNumber), then C-GET
  // (or C-MOVE) of the middle instance. NotFound when the PACS lists none.
  Result<RetrievedSeries> RetrieveInstance(const std::string& study_uid,
                                           const std::string& series_uid,
                                           const std::filesystem::path& folder, int64_t max_bytes,
                                           const CancelToken& cancel) const override;
  // C-STORE of each file (CT, MR and Secondary Capture, explicit VR little
  // endian as vpm writes them).
  Status Store(const std::vector<const std::string*>& files, const ProgressFn& progress,
               const CancelToken& cancel) const override;

  const PacsEndpoint& endpoint() const override { return endpoint_; }

 private:
  // C-GET, or C-MOVE, of the series, or of its instance `sop_uid` when
  // not empty (QueryRetrieveLevel IMAGE).
  Result<RetrievedSeries> GetSeries(const std::string& study_uid, const std::string& series_uid,
                                    const std::string& sop_uid,
                                    const std::filesystem::path& folder, int64_t max_bytes,
                                    int64_t expected_instances, const ProgressFn& progress,
                                    const CancelToken& cancel) const;
  Result<RetrievedSeries> MoveSeries(const std::string& study_uid, const std::string& series_uid,
                                     const std::string& sop_uid,
                                     const std::filesystem::path& folder, int64_t max_bytes,
                                     int64_t expected_instances, const ProgressFn& progress,
                                     const CancelToken& cancel) const;

  PacsEndpoint endpoint_;
  Options options_;
  MoveRegistry* moves_ = nullptr;
};

}  // namespace vpm::pacs

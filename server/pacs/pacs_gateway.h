// What the service asks of the PACS side: the endpoints of the --pacs file,
// who may use each, the DICOMweb client of each, the series cache and the
// audit log. Every action checks the user against the endpoint and is
// audited, allowed or not.
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/pacs/audit_log.h"
#include "server/pacs/dicom_listener.h"
#include "server/pacs/dicomweb_client.h"
#include "server/pacs/dimse_client.h"
#include "server/pacs/move_registry.h"
#include "server/pacs/pacs_endpoint.h"
#include "server/pacs/pacs_source.h"
#include "server/pacs/received_store.h"
#include "server/pacs/series_cache.h"
#include "server/pacs/series_thumbnail.h"
#include "server/pacs/thumbnail_lru.h"
#include "server/volume/volume.h"

namespace vpm::pacs {

// `status` with every mention of `folder` replaced by `name` (a path below
// it reads "name: rest"): messages must not show where the cache or a
// scratch folder lies.
Status HideFolder(const Status& status, const std::filesystem::path& folder,
                  const std::string& name);

class PacsGateway {
 public:
  struct Options {
    std::vector<PacsEndpoint> endpoints;  // at least one
    SeriesCache::Options cache;
    std::filesystem::path audit_log;  // required
    DicomwebClient::Options client;
    DimseClient::Options dimse;
    // vpm's own DICOM node (--dicom-listen): off when `listen.address.port`
    // is 0 and `listen.enabled` false. Needed by "receive" endpoints and
    // "retrieve": "move" ones.
    struct Listen {
      bool enabled = false;
      DimseAddress address;
      std::filesystem::path store_root;            // the received store
      int64_t store_bytes = int64_t{4} << 30;      // its budget
      int max_associations = 8;
      int64_t max_instance_bytes = int64_t{1} << 30;
    } listen;
    // GetSeriesThumbnail: the largest instance retrieved for a thumbnail,
    // bytes, and how long one may take, seconds.
    int64_t thumbnail_instance_bytes = int64_t{64} << 20;
    double thumbnail_deadline_s = 30;
  };
  static Result<std::unique_ptr<PacsGateway>> Create(Options options);

  // The endpoints `user` may use, by name.
  std::vector<std::string> EndpointsFor(const std::string& user) const;

  // PermissionDenied, the same for an unknown endpoint and one the user may
  // not use ("no PACS endpoint 'X' that you may use"), else the client's
  // errors.
  Result<StudySearch> SearchStudies(const std::string& user, const std::string& endpoint,
                                    const StudyQuery& query, const CancelToken& cancel);
  Result<std::vector<SeriesSummary>> ListSeries(const std::string& user,
                                                const std::string& endpoint,
                                                const std::string& study_uid,
                                                const CancelToken& cancel);

  // A grey PNG of one instance of the series (RenderSeriesThumbnail), the
  // longer side `size_px` (0: kDefaultThumbnailPx): from the thumbnails of
  // this run (memory), the series cache, the received store, else one
  // instance retrieved from the PACS (RetrieveInstance) into a scratch
  // folder removed after. Audited as "thumbnail". Errors: PermissionDenied
  // as SearchStudies; InvalidArgument for bad UIDs or size, and for a
  // series without images; ResourceExhausted for an instance over
  // thumbnail_instance_bytes; DeadlineExceeded past thumbnail_deadline_s;
  // the client's. Messages never show the cache's paths.
  Result<SeriesThumbnail> GetSeriesThumbnail(const std::string& user,
                                             const std::string& endpoint,
                                             const std::string& study_uid,
                                             const std::string& series_uid, int size_px,
                                             const CancelToken& cancel);

  // The series `source` names (pacs:NAME/STUDY/SERIES) as a Volume:
  // from the cache, or retrieved (WADO-RS) into it, then read by
  // ReadDicomSeries with `limits` (its read root: the series' folder).
  // The retrieved files must hold images of that series and no other
  // (InvalidArgument otherwise: a structured report, a dose report, a
  // presentation state, or mixed series), else nothing is cached.
  // `progress`: retrieval 0..0.7 (from the instance count the PACS lists),
  // reading 0.7..1. Errors name the series by UID, never the cache's path.
  Result<Volume> LoadSeries(const std::string& user, std::string_view source,
                            const VolumeLimits& limits, const ProgressFn& progress,
                            const CancelToken& cancel);

  // Sends an export's files to `endpoint` (STOW-RS or C-STORE, as the
  // endpoint speaks), audited as "export" with the study and the derived
  // series; PermissionDenied as SearchStudies for an endpoint `user` may
  // not use.
  Status StoreExport(const std::string& user, const std::string& endpoint,
                                 const std::vector<const std::string*>& files,
                                 const std::string& study_uid, const std::string& series_uid,
                                 const ProgressFn& progress, const CancelToken& cancel);
  // Audits an export streamed back to `user` instead of sent.
  void RecordExport(const std::string& user, const std::string& study_uid,
                    const std::string& series_uid, const Status& result, int64_t instances);

  // Audits an open answered with the volume `user` already holds.
  void RecordHeld(const std::string& user, std::string_view source);

  SeriesCache::Stats cache_stats() const { return cache_->stats(); }

  // The port vpm's DICOM node listens on; 0 without --dicom-listen.
  int listen_port() const { return listener_ ? listener_->port() : 0; }
  // Closes the DICOM node's port and cuts its associations (their partial
  // series are dropped); idempotent. The destructor does it too.
  void StopListening() {
    if (listener_) listener_->Stop();
  }

 private:
  PacsGateway() = default;
  Result<const PacsClient*> ClientFor(const std::string& user,
                                          const std::string& endpoint) const;
  Status FetchSeries(const PacsClient& client, const std::string& study_uid,
                     const std::string& series_uid, const std::filesystem::path& folder,
                     int64_t max_bytes, const VolumeLimits& limits, const ProgressFn& progress,
                     const CancelToken& cancel, int64_t* instances);
  Status StartListener(const Options::Listen& listen, const std::vector<PacsEndpoint>& endpoints);
  void RecordReceive(const ReceiveReport& report);
  // Reads the series' files in `folder` (cache or received store) as the
  // volume of `source`.
  Result<Volume> ReadSeriesFolder(const std::filesystem::path& folder, std::string_view source,
                                  const PacsSource& series, const VolumeLimits& limits,
                                  const ProgressFn& progress);

  // GetSeriesThumbnail once permitted: the thumbnail and where it came from.
  Result<SeriesThumbnail> RenderThumbnail(const PacsClient& client, const std::string& study_uid,
                                          const std::string& series_uid, int size_px,
                                          const CancelToken& cancel, std::string* from);

  std::map<std::string, std::unique_ptr<PacsClient>> clients_;  // by endpoint name
  ThumbnailLru thumbnails_;
  int64_t thumbnail_instance_bytes_ = 0;
  double thumbnail_deadline_s_ = 0;
  std::unique_ptr<SeriesCache> cache_;
  std::unique_ptr<AuditLog> audit_;
  std::unique_ptr<ReceivedStore> received_;  // with --dicom-listen
  std::unique_ptr<MoveRegistry> moves_;
  std::unique_ptr<DicomListener> listener_;  // last: stopped first
};

}  // namespace vpm::pacs

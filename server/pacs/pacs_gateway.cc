#include "server/pacs/pacs_gateway.h"

#include <algorithm>
#include <set>

#include "server/io/list_dicom_series.h"
#include "server/io/read_dicom_series.h"
#include "server/pacs/pacs_source.h"
#include "server/pacs/received_client.h"

namespace vpm::pacs {

Status HideFolder(const Status& status, const std::filesystem::path& folder,
                  const std::string& name) {
  if (status.ok()) return status;
  std::string message(status.message());
  for (const std::string& f : {folder.string() + "/", folder.string()}) {
    for (size_t at = message.find(f); at != std::string::npos; at = message.find(f, at)) {
      message.replace(at, f.size(), f.back() == '/' ? name + ": " : name);
      at += name.size();
    }
  }
  return Status(status.code(), message);
}

Result<std::unique_ptr<PacsGateway>> PacsGateway::Create(Options options) {
  if (options.endpoints.empty()) return absl::InvalidArgumentError("--pacs: no endpoints");
  if (options.audit_log.empty()) {
    return absl::InvalidArgumentError(
        "--pacs needs --pacs-audit-log FILE: every PACS action is audited");
  }
  std::unique_ptr<PacsGateway> gateway(new PacsGateway());
  gateway->thumbnail_instance_bytes_ = options.thumbnail_instance_bytes;
  gateway->thumbnail_deadline_s_ = options.thumbnail_deadline_s;
  ASSIGN_OR_RETURN(gateway->audit_, AuditLog::Open(options.audit_log));
  ASSIGN_OR_RETURN(gateway->cache_, SeriesCache::Create(options.cache));
  RETURN_IF_ERROR(gateway->StartListener(options.listen, options.endpoints));
  for (PacsEndpoint& endpoint : options.endpoints) {
    const std::string name = endpoint.name;
    if (endpoint.receive) {
      gateway->clients_[name] =
          std::make_unique<ReceivedClient>(std::move(endpoint), gateway->received_.get());
    } else if (endpoint.dimse_host.empty()) {
      gateway->clients_[name] =
          std::make_unique<DicomwebClient>(std::move(endpoint), options.client);
    } else {
      gateway->clients_[name] = std::make_unique<DimseClient>(std::move(endpoint), options.dimse,
                                                              gateway->moves_.get());
    }
  }
  return gateway;
}

Status PacsGateway::StartListener(const Options::Listen& listen,
                                  const std::vector<PacsEndpoint>& endpoints) {
  std::set<std::string> move_originators;
  for (const PacsEndpoint& e : endpoints) {
    if ((e.receive || e.retrieve_by_move) && !listen.enabled) {
      return absl::InvalidArgumentError(StrCat(
          "--pacs: endpoint '", e.name, "' ",
          e.receive ? "(\"receive\": true) shows what DICOM nodes send to vpm"
                    : "(\"retrieve\": \"move\") has the PACS send the series to vpm",
          ", which needs vpm-server --dicom-listen AET@HOST:PORT"));
    }
    if (e.retrieve_by_move) move_originators.insert(e.calling_ae_title);
  }
  if (!listen.enabled) return absl::OkStatus();
  ASSIGN_OR_RETURN(received_, ReceivedStore::Create({.root = listen.store_root,
                                                     .max_bytes = listen.store_bytes}));
  moves_ = std::make_unique<MoveRegistry>();
  ASSIGN_OR_RETURN(listener_,
                   DicomListener::Start({.address = listen.address,
                                         .max_associations = listen.max_associations,
                                         .max_instance_bytes = listen.max_instance_bytes,
                                         .store = received_.get(),
                                         .moves = moves_.get(),
                                         .own_move_originators = move_originators,
                                         .on_series = [this](const ReceiveReport& report) {
                                           RecordReceive(report);
                                         }}));
  return absl::OkStatus();
}

void PacsGateway::RecordReceive(const ReceiveReport& report) {
  audit_->Record({.action = "receive",
                  .study_uid = report.study_uid,
                  .series_uid = report.series_uid,
                  .result = report.result,
                  .instances = report.instances,
                  .calling_aet = report.calling_ae,
                  .refused = report.refused});
}

std::vector<std::string> PacsGateway::EndpointsFor(const std::string& user) const {
  std::vector<std::string> out;
  for (const auto& [name, client] : clients_) {
    if (client->endpoint().AllowsUser(user)) out.push_back(name);
  }
  return out;
}

Result<const PacsClient*> PacsGateway::ClientFor(const std::string& user,
                                                     const std::string& endpoint) const {
  auto it = clients_.find(endpoint);
  if (it == clients_.end() || !it->second->endpoint().AllowsUser(user)) {
    // The same answer for both: users do not learn which endpoints exist.
    return absl::PermissionDeniedError(
        StrCat("endpoint: no PACS endpoint '", endpoint.substr(0, 64), "' that you may use"));
  }
  return it->second.get();
}

Result<StudySearch> PacsGateway::SearchStudies(const std::string& user, const std::string& endpoint,
                                               const StudyQuery& query, const CancelToken& cancel) {
  AuditRecord record{
      .user = user, .action = "search", .endpoint = endpoint, .filters = StudyQueryFilters(query)};
  Result<StudySearch> result = [&]() -> Result<StudySearch> {
    ASSIGN_OR_RETURN(const PacsClient* client, ClientFor(user, endpoint));
    return client->SearchStudies(query, cancel);
  }();
  record.result = result.status();
  if (result.ok()) record.matches = static_cast<int64_t>(result->studies.size());
  audit_->Record(record);
  return result;
}

Result<std::vector<SeriesSummary>> PacsGateway::ListSeries(const std::string& user,
                                                           const std::string& endpoint,
                                                           const std::string& study_uid,
                                                           const CancelToken& cancel) {
  AuditRecord record{.user = user,
                     .action = "series",
                     .endpoint = endpoint,
                     .study_uid = CheckUid(study_uid, "").ok() ? study_uid : ""};
  Result<std::vector<SeriesSummary>> result = [&]() -> Result<std::vector<SeriesSummary>> {
    ASSIGN_OR_RETURN(const PacsClient* client, ClientFor(user, endpoint));
    return client->ListSeries(study_uid, cancel);
  }();
  record.result = result.status();
  if (result.ok()) record.matches = static_cast<int64_t>(result->size());
  audit_->Record(record);
  return result;
}

Status PacsGateway::FetchSeries(const PacsClient& client, const std::string& study_uid,
                                const std::string& series_uid, const std::filesystem::path& folder,
                                int64_t max_bytes, const VolumeLimits& limits,
                                const ProgressFn& progress, const CancelToken& cancel,
                                int64_t* instances) {
  const std::string label = EndpointLabel(client.endpoint());
  // The listing says whether the series is there and how many instances
  // to expect (progress).
  ASSIGN_OR_RETURN(const std::vector<SeriesSummary> listed, client.ListSeries(study_uid, cancel));
  auto it = std::find_if(listed.begin(), listed.end(),
                         [&](const SeriesSummary& s) { return s.series_uid == series_uid; });
  if (it == listed.end()) {
    return absl::NotFoundError(
        StrCat(label, ": study ", study_uid, " holds no series ", series_uid));
  }
  ASSIGN_OR_RETURN(const RetrievedSeries got,
                   client.RetrieveSeries(study_uid, series_uid, folder, max_bytes,
                                         it->instance_count, progress, cancel));
  *instances = got.instances;
  // Only a series of images that vpm reads, and only this one, is cached.
  const std::string name = StrCat("series ", series_uid);
  Result<std::vector<DicomSeriesSummary>> groups = ListDicomSeries(folder, limits);
  if (!groups.ok()) {
    if (absl::IsInvalidArgument(groups.status()) &&
        groups.status().message().find("no DICOM images") != std::string_view::npos) {
      return absl::InvalidArgumentError(
          StrCat(label, ": ", name, " (", it->modality.empty() ? "no modality" : it->modality, ", ",
                 got.instances,
                 " instances) holds no images: a structured report, a dose report or a "
                 "presentation state is not a volume"));
    }
    return HideFolder(groups.status(), folder, name);
  }
  for (const DicomSeriesSummary& group : *groups) {
    if (group.uid != series_uid) {
      return absl::InvalidArgumentError(StrCat(label, ": asked for ", name,
                                               ", the PACS sent instances of series '",
                                               group.uid.substr(0, 64), "' too; nothing was kept"));
    }
  }
  return absl::OkStatus();
}

Result<Volume> PacsGateway::ReadSeriesFolder(const std::filesystem::path& folder,
                                             std::string_view source, const PacsSource& series,
                                             const VolumeLimits& limits,
                                             const ProgressFn& progress) {
  VolumeLimits read_limits = limits;
  std::error_code error;
  read_limits.read_root = std::filesystem::canonical(folder, error);
  if (error) return absl::InternalError("the PACS cache lost a series folder");
  if (progress) progress(0.7, "reading");
  DicomReadOptions options{.series = series.series_uid, .stack = series.stack};
  Result<Volume> volume = ReadDicomSeries(read_limits.read_root, read_limits, options);
  if (!volume.ok()) {
    return HideFolder(volume.status(), read_limits.read_root, StrCat("series ", series.series_uid));
  }
  volume->set_source(std::string(source));
  if (progress) progress(1.0, "reading");
  return volume;
}

Result<Volume> PacsGateway::LoadSeries(const std::string& user, std::string_view source,
                                       const VolumeLimits& limits, const ProgressFn& progress,
                                       const CancelToken& cancel) {
  AuditRecord record{.user = user, .action = "open"};
  Result<Volume> result = [&]() -> Result<Volume> {
    ASSIGN_OR_RETURN(const PacsSource s, ParsePacsSource(source));
    record.endpoint = s.endpoint;
    record.study_uid = s.study_uid;
    record.series_uid = s.series_uid;
    ASSIGN_OR_RETURN(const PacsClient* client, ClientFor(user, s.endpoint));
    if (const auto* received = dynamic_cast<const ReceivedClient*>(client)) {
      // Received series are read where they are, held unchanged meanwhile.
      ASSIGN_OR_RETURN(std::shared_ptr<ReceivedStore::Lease> lease,
                       received->OpenSeries(s.study_uid, s.series_uid));
      record.cache = "received";
      record.instances = lease->instances;
      return ReadSeriesFolder(lease->folder, source, s, limits, progress);
    }
    int64_t instances = -1;
    ASSIGN_OR_RETURN(std::shared_ptr<const SeriesCache::Lease> lease,
                     cache_->Open(
                         s.endpoint, s.series_uid,
                         [&](const std::filesystem::path& folder, int64_t max_bytes) {
                           return FetchSeries(*client, s.study_uid, s.series_uid, folder, max_bytes,
                                              limits, SubProgress(progress, 0.0, 0.7), cancel,
                                              &instances);
                         },
                         cancel));
    record.cache = lease->hit ? "hit" : "miss";
    RETURN_IF_ERROR(cancel.Check());
    Result<Volume> volume = ReadSeriesFolder(lease->folder, source, s, limits, progress);
    if (instances < 0) {
      std::error_code error;
      instances = static_cast<int64_t>(
          std::distance(std::filesystem::directory_iterator(lease->folder, error),
                        std::filesystem::directory_iterator()));
    }
    record.instances = instances;
    return volume;
  }();
  record.result = result.status();
  audit_->Record(record);
  return result;
}

Status PacsGateway::StoreExport(const std::string& user, const std::string& endpoint,
                                            const std::vector<const std::string*>& files,
                                            const std::string& study_uid,
                                            const std::string& series_uid,
                                            const ProgressFn& progress,
                                            const CancelToken& cancel) {
  AuditRecord record{.user = user, .action = "export", .endpoint = endpoint,
                     .study_uid = study_uid, .series_uid = series_uid,
                     .instances = static_cast<int64_t>(files.size())};
  Status result = [&]() -> Status {
    ASSIGN_OR_RETURN(const PacsClient* client, ClientFor(user, endpoint));
    return client->Store(files, progress, cancel);
  }();
  record.result = result;
  audit_->Record(record);
  return result;
}

void PacsGateway::RecordExport(const std::string& user, const std::string& study_uid,
                               const std::string& series_uid, const Status& result,
                               int64_t instances) {
  audit_->Record({.user = user, .action = "export", .study_uid = study_uid,
                  .series_uid = series_uid, .result = result, .instances = instances});
}

void PacsGateway::RecordHeld(const std::string& user, std::string_view source) {
  AuditRecord record{.user = user, .action = "open", .cache = "held"};
  if (Result<PacsSource> s = ParsePacsSource(source); s.ok()) {
    record.endpoint = s->endpoint;
    record.study_uid = s->study_uid;
    record.series_uid = s->series_uid;
  }
  audit_->Record(record);
}

}  // namespace vpm::pacs

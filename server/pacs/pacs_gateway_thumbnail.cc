// PacsGateway::GetSeriesThumbnail: one instance of a series, from wherever
// it is nearest, rendered small (series_thumbnail.h).
#include <algorithm>
#include <chrono>
#include <system_error>

#include "server/io/read_file_bytes.h"
#include "server/pacs/pacs_gateway.h"
#include "server/pacs/received_client.h"

namespace vpm::pacs {
namespace {

// The middle regular file of `folder` by name, the instance a thumbnail of
// a cached or received series shows; empty when there is none.
std::filesystem::path MiddleFile(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    if (entry.is_regular_file(error)) files.push_back(entry.path());
  }
  if (files.empty()) return {};
  std::sort(files.begin(), files.end());
  return files[files.size() / 2];
}

// `cancel`, and DeadlineExceeded once `seconds` have passed.
CancelToken WithDeadline(const CancelToken& cancel, double seconds) {
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int64_t>(seconds * 1000));
  return CancelToken([cancel, until, seconds]() -> Status {
    RETURN_IF_ERROR(cancel.Check());
    if (std::chrono::steady_clock::now() > until) {
      return absl::DeadlineExceededError(
          StrCat("the thumbnail took over ", seconds, " s (the PACS is slow)"));
    }
    return absl::OkStatus();
  });
}

// The thumbnail of the file at `path`, named `name` in messages.
Result<SeriesThumbnail> ThumbnailOfFile(const std::filesystem::path& path, int size_px,
                                        int64_t max_bytes, const CancelToken& cancel,
                                        const std::string& name) {
  if (path.empty()) return absl::NotFoundError(StrCat(name, ": no instance"));
  const VolumeLimits limits{.max_bytes = max_bytes, .cancel = cancel};
  Result<std::vector<uint8_t>> bytes = ReadFileBytes(path, limits);
  if (!bytes.ok()) {
    return Status(bytes.status().code(), StrCat(name, ": the instance cannot be read"));
  }
  Result<SeriesThumbnail> thumbnail = RenderSeriesThumbnail(*bytes, size_px, limits);
  if (!thumbnail.ok()) {
    return Status(thumbnail.status().code(), StrCat(name, ": ", thumbnail.status().message()));
  }
  return thumbnail;
}

}  // namespace

Result<SeriesThumbnail> PacsGateway::GetSeriesThumbnail(const std::string& user,
                                                        const std::string& endpoint,
                                                        const std::string& study_uid,
                                                        const std::string& series_uid,
                                                        int size_px, const CancelToken& cancel) {
  AuditRecord record{.user = user,
                     .action = "thumbnail",
                     .endpoint = endpoint,
                     .study_uid = CheckUid(study_uid, "").ok() ? study_uid : "",
                     .series_uid = CheckUid(series_uid, "").ok() ? series_uid : ""};
  Result<SeriesThumbnail> result = [&]() -> Result<SeriesThumbnail> {
    ASSIGN_OR_RETURN(const PacsClient* client, ClientFor(user, endpoint));
    RETURN_IF_ERROR(CheckUid(study_uid, "study_uid"));
    RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
    const int size = size_px == 0 ? kDefaultThumbnailPx : size_px;
    if (size < 16 || size > kMaxThumbnailPx) {
      return absl::InvalidArgumentError(
          StrCat("size_px: ", size_px, " is outside 16..", kMaxThumbnailPx, " (0: ",
                 kDefaultThumbnailPx, ")"));
    }
    const std::string key = StrCat(endpoint, "/", series_uid, "/", size);
    if (std::optional<SeriesThumbnail> known = thumbnails_.Find(key)) {
      record.cache = "memory";
      return *std::move(known);
    }
    ASSIGN_OR_RETURN(SeriesThumbnail made,
                     RenderThumbnail(*client, study_uid, series_uid, size,
                                     WithDeadline(cancel, thumbnail_deadline_s_), &record.cache));
    thumbnails_.Put(key, made);
    return made;
  }();
  record.result = result.status();
  audit_->Record(record);
  return result;
}

Result<SeriesThumbnail> PacsGateway::RenderThumbnail(const PacsClient& client,
                                                     const std::string& study_uid,
                                                     const std::string& series_uid, int size_px,
                                                     const CancelToken& cancel,
                                                     std::string* from) {
  const std::string name = StrCat(EndpointLabel(client.endpoint()), ": series ", series_uid);
  const int64_t cap = thumbnail_instance_bytes_;
  if (const auto* received = dynamic_cast<const ReceivedClient*>(&client)) {
    ASSIGN_OR_RETURN(std::shared_ptr<ReceivedStore::Lease> lease,
                     received->OpenSeries(study_uid, series_uid));
    *from = "received";
    return ThumbnailOfFile(MiddleFile(lease->folder), size_px, cap, cancel, name);
  }
  if (std::shared_ptr<const SeriesCache::Lease> lease =
          cache_->Find(client.endpoint().name, series_uid)) {
    *from = "cache";
    return ThumbnailOfFile(MiddleFile(lease->folder), size_px, cap, cancel, name);
  }
  *from = "pacs";
  ASSIGN_OR_RETURN(const std::filesystem::path scratch, cache_->MakeScratchFolder());
  Result<SeriesThumbnail> out = [&]() -> Result<SeriesThumbnail> {
    Result<RetrievedSeries> got =
        client.RetrieveInstance(study_uid, series_uid, scratch, cap, cancel);
    if (!got.ok()) return HideFolder(got.status(), scratch, name);
    return ThumbnailOfFile(MiddleFile(scratch), size_px, cap, cancel, name);
  }();
  std::error_code error;
  std::filesystem::remove_all(scratch, error);
  return out;
}

}  // namespace vpm::pacs

#include "server/pacs/series_cache.h"

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <vector>

#include "server/pacs/pacs_endpoint.h"
#include "server/pacs/study_query.h"

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;

int64_t FolderBytes(const fs::path& folder) {
  int64_t total = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(folder, error)) {
    std::error_code size_error;
    if (entry.is_regular_file(size_error))
      total += static_cast<int64_t>(entry.file_size(size_error));
  }
  return total;
}

std::string SystemError(const std::error_code& error) { return error.message(); }

}  // namespace

SeriesCache::SeriesCache(Options options)
    : options_(std::move(options)), state_(std::make_shared<State>()) {}

SeriesCache::~SeriesCache() {
  if (options_.remove_root_on_destroy) {
    std::error_code error;
    fs::remove_all(options_.root, error);
  }
}

Result<std::unique_ptr<SeriesCache>> SeriesCache::Create(const Options& options) {
  if (options.root.empty()) return absl::InvalidArgumentError("the PACS cache needs a folder");
  if (options.max_bytes < 1) {
    return absl::InvalidArgumentError("--pacs-cache-bytes: must be positive");
  }
  std::error_code error;
  fs::create_directories(options.root, error);
  if (error) {
    return absl::InvalidArgumentError(
        StrCat("--pacs-cache ", options.root.string(), ": cannot create: ", SystemError(error)));
  }
  ::chmod(options.root.c_str(), 0700);  // patients' images: the server's user only
  std::unique_ptr<SeriesCache> cache(new SeriesCache(options));
  RETURN_IF_ERROR(cache->Scan());
  return cache;
}

Status SeriesCache::Scan() {
  std::error_code error;
  std::vector<std::pair<fs::file_time_type, std::string>> found;
  for (const auto& endpoint : fs::directory_iterator(options_.root, error)) {
    const std::string name = endpoint.path().filename().string();
    if (name.starts_with(".tmp-")) {
      fs::remove_all(endpoint.path(), error);
      continue;
    }
    if (!endpoint.is_directory() || !CheckEndpointName(name).ok()) continue;
    for (const auto& series : fs::directory_iterator(endpoint.path(), error)) {
      const std::string uid = series.path().filename().string();
      if (!series.is_directory() || !CheckUid(uid, "").ok()) continue;
      const std::string key = name + "/" + uid;
      Entry entry{.folder = series.path(), .bytes = FolderBytes(series.path())};
      state_->bytes += entry.bytes;
      state_->entries[key] = entry;
      std::error_code time_error;
      found.emplace_back(fs::last_write_time(series.path(), time_error), key);
    }
  }
  if (error) {
    return absl::InvalidArgumentError(
        StrCat("--pacs-cache ", options_.root.string(), ": cannot list: ", SystemError(error)));
  }
  std::sort(found.begin(), found.end());
  for (const auto& [time, key] : found) state_->entries[key].last_use = ++state_->tick;
  std::lock_guard lock(state_->mutex);
  // Over a budget lowered since the last run: the oldest go now.
  (void)MakeRoomLocked(0);
  return absl::OkStatus();
}

Status SeriesCache::MakeRoomLocked(int64_t extra) {
  State& s = *state_;
  if (extra > options_.max_bytes) {
    return absl::ResourceExhaustedError(StrCat("the series is ", extra,
                                               " bytes, over the PACS cache's budget of ",
                                               options_.max_bytes, " bytes (--pacs-cache-bytes)"));
  }
  while (s.bytes + extra > options_.max_bytes) {
    auto lru = s.entries.end();
    for (auto it = s.entries.begin(); it != s.entries.end(); ++it) {
      if (it->second.pins == 0 &&
          (lru == s.entries.end() || it->second.last_use < lru->second.last_use)) {
        lru = it;
      }
    }
    if (lru == s.entries.end()) {
      return absl::ResourceExhaustedError(
          StrCat("the PACS cache (", options_.max_bytes,
                 " bytes, --pacs-cache-bytes) is full of series being read; try again later"));
    }
    std::error_code error;
    fs::remove_all(lru->second.folder, error);
    s.bytes -= lru->second.bytes;
    ++s.stats.evictions;
    s.entries.erase(lru);
  }
  return absl::OkStatus();
}

std::shared_ptr<const SeriesCache::Lease> SeriesCache::PinLocked(const std::string& key, bool hit) {
  Entry& entry = state_->entries.at(key);
  ++entry.pins;
  entry.last_use = ++state_->tick;
  auto lease = new Lease{.folder = entry.folder, .hit = hit, .bytes = entry.bytes};
  // The lease may outlive the cache object: it holds the state, not `this`.
  return std::shared_ptr<const Lease>(lease, [state = state_, key](const Lease* l) {
    {
      std::lock_guard lock(state->mutex);
      auto it = state->entries.find(key);
      if (it != state->entries.end() && it->second.pins > 0) --it->second.pins;
    }
    delete l;
  });
}

Status SeriesCache::FetchInto(const std::string& key, const fs::path& final_folder,
                              const Fetch& fetch, int64_t* bytes) {
  std::string pattern = (options_.root / ".tmp-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    return absl::InternalError("the PACS cache: cannot make a temporary folder");
  }
  const fs::path temp(pattern);
  std::error_code error;
  Status status = fetch(temp, options_.max_bytes);
  if (status.ok()) {
    *bytes = FolderBytes(temp);
    std::lock_guard lock(state_->mutex);
    status = MakeRoomLocked(*bytes);
    if (status.ok()) {
      fs::create_directories(final_folder.parent_path(), error);
      fs::remove_all(final_folder, error);  // a leftover the index does not know
      fs::rename(temp, final_folder, error);
      if (error) {
        status = absl::InternalError(
            StrCat("the PACS cache: cannot rename into place: ", SystemError(error)));
      } else {
        state_->entries[key] = Entry{.folder = final_folder, .bytes = *bytes};
        state_->bytes += *bytes;
      }
    }
  }
  if (!status.ok()) fs::remove_all(temp, error);
  return status;
}

Result<std::shared_ptr<const SeriesCache::Lease>> SeriesCache::Open(const std::string& endpoint,
                                                                    const std::string& series_uid,
                                                                    const Fetch& fetch,
                                                                    const CancelToken& cancel) {
  RETURN_IF_ERROR(CheckEndpointName(endpoint));
  RETURN_IF_ERROR(CheckUid(series_uid, "series_uid"));
  const std::string key = endpoint + "/" + series_uid;
  State& s = *state_;
  std::shared_ptr<InFlight> mine;
  {
    std::unique_lock lock(s.mutex);
    while (true) {
      if (s.entries.contains(key)) {
        ++s.stats.hits;
        return PinLocked(key, /*hit=*/true);
      }
      auto flight = s.in_flight.find(key);
      if (flight == s.in_flight.end()) break;
      std::shared_ptr<InFlight> theirs = flight->second;
      while (!theirs->done) {
        s.changed.wait_for(lock, std::chrono::milliseconds(100));
        if (Status gone = cancel.Check(); !gone.ok()) return gone;
      }
      const Status& result = theirs->status;
      if (!result.ok() && !absl::IsCancelled(result) && !absl::IsDeadlineExceeded(result) &&
          !absl::IsUnavailable(result)) {
        return result;
      }
      // Cached now, or the other open gave up: look again.
    }
    mine = std::make_shared<InFlight>();
    s.in_flight[key] = mine;
    ++s.stats.fetches;
  }
  int64_t bytes = 0;
  Status status = FetchInto(key, options_.root / endpoint / series_uid, fetch, &bytes);
  std::lock_guard lock(s.mutex);
  mine->done = true;
  mine->status = status;
  s.in_flight.erase(key);
  s.changed.notify_all();
  if (!status.ok()) return status;
  return PinLocked(key, /*hit=*/false);
}

std::shared_ptr<const SeriesCache::Lease> SeriesCache::Find(const std::string& endpoint,
                                                            const std::string& series_uid) {
  const std::string key = endpoint + "/" + series_uid;
  std::lock_guard lock(state_->mutex);
  if (!state_->entries.contains(key)) return nullptr;
  return PinLocked(key, /*hit=*/true);
}

Result<fs::path> SeriesCache::MakeScratchFolder() const {
  std::string pattern = (options_.root / ".tmp-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    return absl::InternalError("the PACS cache: cannot make a temporary folder");
  }
  return fs::path(pattern);
}

SeriesCache::Stats SeriesCache::stats() const {
  std::lock_guard lock(state_->mutex);
  Stats out = state_->stats;
  out.entries = static_cast<int64_t>(state_->entries.size());
  out.bytes = state_->bytes;
  return out;
}

}  // namespace vpm::pacs

// Retrieved series on disk, by endpoint and Series Instance UID, under a
// byte budget, least recently used out. A series enters the cache only
// whole: it is fetched into a temporary folder and renamed into place once
// complete and checked, so a cut transfer, a cancelled load or a series that
// fails its checks leaves nothing behind. Two opens of one series at once
// fetch it once: the second waits for the first.
//
// Layout: ROOT/ENDPOINT/SERIES_UID/*.dcm; fetches in ROOT/.tmp-XXXXXX.
// A cache folder found at start is taken as it is (its folders were
// complete when renamed), temporary folders are removed.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "server/common/cancel_token.h"
#include "server/common/status.h"

namespace vpm::pacs {

class SeriesCache {
 public:
  struct Options {
    std::filesystem::path root;            // created (mode 0700) if missing
    int64_t max_bytes = int64_t{4} << 30;  // the budget, bytes of files
    bool remove_root_on_destroy = false;   // a temporary cache of one run
  };
  static Result<std::unique_ptr<SeriesCache>> Create(const Options& options);
  ~SeriesCache();

  // A complete series folder, pinned (never evicted) while held.
  struct Lease {
    std::filesystem::path folder;
    bool hit = false;  // found in the cache (or fetched by another open)
    int64_t bytes = 0;
  };
  // Fills `folder` (empty, existing) with the series' files, at most
  // `max_bytes` of them; an error leaves nothing cached.
  using Fetch = std::function<Status(const std::filesystem::path& folder, int64_t max_bytes)>;

  // The series `endpoint`/`series_uid` (both checked: CheckEndpointName,
  // CheckUid), fetched by `fetch` when not cached. Errors: fetch's (also
  // given to opens that waited for it, unless it was cancelled: they then
  // fetch themselves); ResourceExhausted when the series is over the budget
  // or everything else is pinned; Internal for file system failures;
  // `cancel`'s status while waiting.
  Result<std::shared_ptr<const Lease>> Open(const std::string& endpoint,
                                            const std::string& series_uid, const Fetch& fetch,
                                            const CancelToken& cancel = {});

  // The series when it is cached, pinned, else nullptr; fetches nothing and
  // counts as no hit (a thumbnail peeks before retrieving one instance).
  std::shared_ptr<const Lease> Find(const std::string& endpoint,
                                    const std::string& series_uid);

  // A new empty folder under the cache's root (ROOT/.tmp-XXXXXX, removed at
  // the next start if left behind); the caller removes it. Internal when it
  // cannot be made.
  Result<std::filesystem::path> MakeScratchFolder() const;

  struct Stats {
    int64_t entries = 0;
    int64_t bytes = 0;
    int64_t hits = 0;     // opens answered from the cache
    int64_t fetches = 0;  // fetches started
    int64_t evictions = 0;
  };
  Stats stats() const;

 private:
  struct Entry {
    std::filesystem::path folder;
    int64_t bytes = 0;
    int64_t last_use = 0;
    int32_t pins = 0;
  };
  struct InFlight {
    bool done = false;
    Status status;
  };
  struct State {
    std::mutex mutex;
    std::condition_variable changed;
    std::map<std::string, Entry> entries;  // by "ENDPOINT/UID"
    std::map<std::string, std::shared_ptr<InFlight>> in_flight;
    int64_t bytes = 0, tick = 0;
    Stats stats;
  };
  explicit SeriesCache(Options options);
  Status Scan();
  // Evicts unpinned entries, least recently used first, until `extra`
  // more bytes fit; ResourceExhausted when they cannot.
  Status MakeRoomLocked(int64_t extra);
  std::shared_ptr<const Lease> PinLocked(const std::string& key, bool hit);
  Status FetchInto(const std::string& key, const std::filesystem::path& final_folder,
                   const Fetch& fetch, int64_t* bytes);

  Options options_;
  std::shared_ptr<State> state_;
};

}  // namespace vpm::pacs

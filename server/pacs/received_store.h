// The series that DICOM nodes sent to vpm's listener (C-STORE), on disk
// under a byte budget, with an index of their study and series attributes
// that "receive" endpoints search. A series becomes visible only whole:
// an association's instances wait in a temporary folder of their own and
// enter the store when the association is released (Commit), never half.
//
// Layout: ROOT/series/SERIES_UID/NNNNNN.dcm (names vpm makes; UIDs checked
// by CheckUid before they name a folder), ROOT/index/SERIES_UID.json (the
// attributes, written after the folder is in place), ROOT/.tmp-XXXXXX (an
// association's instances). At start, temporary folders and series without
// an index entry (a commit cut short) are removed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "server/common/status.h"
#include "server/pacs/pacs_client.h"
#include "server/pacs/received_instance.h"

namespace vpm::pacs {

// One received series as the index keeps it.
struct ReceivedSeriesRecord {
  ReceivedInstance attributes;        // of its first instance (study, patient, series)
  std::string calling_ae;             // the node that sent it first
  std::vector<std::string> sop_uids;  // its instances, in file order
  int64_t bytes = 0;                  // bytes of its files
};

class ReceivedStore {
 public:
  struct Options {
    std::filesystem::path root;            // created (mode 0700) if missing
    int64_t max_bytes = int64_t{4} << 30;  // complete series plus reservations
  };
  static Result<std::unique_ptr<ReceivedStore>> Create(const Options& options);

  // A private temporary folder (ROOT/.tmp-XXXXXX) for one association's
  // instances, removed with the object.
  class Incoming {
   public:
    ~Incoming();
    const std::filesystem::path& folder() const { return folder_; }

   private:
    friend class ReceivedStore;
    explicit Incoming(std::filesystem::path folder) : folder_(std::move(folder)) {}
    std::filesystem::path folder_;
  };
  Result<std::unique_ptr<Incoming>> BeginIncoming() const;

  // Reserves `bytes` of the budget for an instance being kept;
  // ResourceExhausted when stored series and reservations would pass it.
  Status Reserve(int64_t bytes);
  void Release(int64_t bytes);

  // One series of an association, its files in an Incoming folder.
  struct SeriesFiles {
    ReceivedInstance attributes;
    std::string calling_ae;
    std::vector<std::pair<std::filesystem::path, std::string>> files;  // path, SOP UID
    int64_t bytes = 0;  // reserved for them (released by Commit)
  };
  // Moves the files into the series' folder (new, or added to what was
  // received before; an instance whose SOP Instance UID is there already
  // is dropped) and writes its index entry. Returns the instances added.
  // Internal for file system failures (the series is then left as it was).
  Result<int64_t> Commit(const SeriesFiles& series);

  // The studies and series whose sender is in `from` (empty: any), as a
  // PACS would answer C-FIND (wildcards '*' '?' in names and IDs, case
  // insensitive names, date ranges, ModalitiesInStudy).
  StudySearch Search(const StudyQuery& query, const std::vector<std::string>& from) const;
  std::vector<SeriesSummary> ListSeries(const std::string& study_uid,
                                        const std::vector<std::string>& from) const;

  // A complete series folder, kept as it is (no commit adds to it) while
  // held. NotFound for a series not received (or not from `from`).
  struct Lease {
    std::filesystem::path folder;
    int64_t instances = 0;
    std::shared_lock<std::shared_mutex> hold;
  };
  Result<std::shared_ptr<Lease>> OpenSeries(const std::string& study_uid,
                                            const std::string& series_uid,
                                            const std::vector<std::string>& from) const;

  int64_t stored_bytes() const;

 private:
  explicit ReceivedStore(Options options) : options_(std::move(options)) {}
  Status Scan();
  Status WriteIndex(const ReceivedSeriesRecord& record) const;

  Options options_;
  mutable std::mutex mutex_;               // the index and the byte counts
  mutable std::shared_mutex files_mutex_;  // commits (exclusive) and reads (shared)
  std::map<std::string, ReceivedSeriesRecord> series_;  // by series UID
  int64_t stored_bytes_ = 0, reserved_bytes_ = 0;
};

// DICOM matching of one value: '*' any run, '?' one character;
// `fold_case` for person names.
bool MatchesWildcard(std::string_view pattern, std::string_view value, bool fold_case);
// A date YYYYMMDD against "YYYYMMDD", "FROM-TO", "FROM-" or "-TO" (empty:
// any).
bool MatchesDateRange(std::string_view range, std::string_view date);

}  // namespace vpm::pacs

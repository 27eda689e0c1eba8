#include "server/pacs/received_store.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "server/pacs/study_query.h"

namespace vpm::pacs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json RecordToJson(const ReceivedSeriesRecord& r) {
  const ReceivedInstance& a = r.attributes;
  return {{"study_uid", a.study_uid},
          {"series_uid", a.series_uid},
          {"patient_name", a.patient_name},
          {"patient_id", a.patient_id},
          {"patient_birth_date", a.patient_birth_date},
          {"study_date", a.study_date},
          {"study_description", a.study_description},
          {"accession_number", a.accession_number},
          {"modality", a.modality},
          {"series_description", a.series_description},
          {"body_part", a.body_part},
          {"series_number", a.series_number},
          {"calling_ae", r.calling_ae},
          {"sop_uids", r.sop_uids},
          {"bytes", r.bytes}};
}

Result<ReceivedSeriesRecord> RecordFromJson(const json& j) {
  if (!j.is_object()) return absl::InvalidArgumentError("not an object");
  const auto text = [&](const char* key) {
    return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
  };
  ReceivedSeriesRecord r;
  r.attributes = {.study_uid = text("study_uid"),
                  .series_uid = text("series_uid"),
                  .patient_name = text("patient_name"),
                  .patient_id = text("patient_id"),
                  .patient_birth_date = text("patient_birth_date"),
                  .study_date = text("study_date"),
                  .study_description = text("study_description"),
                  .accession_number = text("accession_number"),
                  .modality = text("modality"),
                  .series_description = text("series_description"),
                  .body_part = text("body_part")};
  if (j.contains("series_number") && j["series_number"].is_number_integer()) {
    r.attributes.series_number = j["series_number"].get<int64_t>();
  }
  r.calling_ae = text("calling_ae");
  if (!j.contains("sop_uids") || !j["sop_uids"].is_array()) {
    return absl::InvalidArgumentError("no sop_uids");
  }
  for (const json& uid : j["sop_uids"]) {
    if (uid.is_string()) r.sop_uids.push_back(uid.get<std::string>());
  }
  if (j.contains("bytes") && j["bytes"].is_number_integer()) r.bytes = j["bytes"].get<int64_t>();
  RETURN_IF_ERROR(CheckUid(r.attributes.study_uid, "study_uid"));
  RETURN_IF_ERROR(CheckUid(r.attributes.series_uid, "series_uid"));
  return r;
}

bool FromAllowed(const std::vector<std::string>& from, const std::string& calling_ae) {
  return from.empty() || std::find(from.begin(), from.end(), calling_ae) != from.end();
}

std::string InstanceName(size_t n) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.dcm", n);
  return name;
}

// Rename, or copy and remove across file systems.
std::error_code MoveFile(const fs::path& from, const fs::path& to) {
  std::error_code error;
  fs::rename(from, to, error);
  if (!error) return error;
  error.clear();
  fs::copy_file(from, to, fs::copy_options::overwrite_existing, error);
  if (!error) fs::remove(from, error);
  return error;
}

bool StudyMatches(const StudyQuery& q, const ReceivedInstance& a) {
  return (q.patient_name.empty() || MatchesWildcard(q.patient_name, a.patient_name, true)) &&
         (q.patient_id.empty() || MatchesWildcard(q.patient_id, a.patient_id, false)) &&
         (q.accession_number.empty() ||
          MatchesWildcard(q.accession_number, a.accession_number, false)) &&
         MatchesDateRange(q.patient_birth_date, a.patient_birth_date) &&
         MatchesDateRange(q.study_date, a.study_date);
}

}  // namespace

bool MatchesWildcard(std::string_view pattern, std::string_view value, bool fold_case) {
  const auto same = [fold_case](char p, char v) {
    return fold_case ? std::tolower(static_cast<unsigned char>(p)) ==
                           std::tolower(static_cast<unsigned char>(v))
                     : p == v;
  };
  // Iterative matching with one backtrack point (the last '*').
  size_t p = 0, v = 0, star = std::string_view::npos, mark = 0;
  while (v < value.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || (pattern[p] != '*' && same(pattern[p], value[v])))) {
      ++p;
      ++v;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = v;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      v = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

bool MatchesDateRange(std::string_view range, std::string_view date) {
  if (range.empty()) return true;
  const size_t dash = range.find('-');
  if (dash == std::string_view::npos) return date == range;
  if (date.empty()) return false;
  const std::string_view from = range.substr(0, dash), to = range.substr(dash + 1);
  return (from.empty() || date >= from) && (to.empty() || date <= to);
}

ReceivedStore::Incoming::~Incoming() {
  std::error_code error;
  fs::remove_all(folder_, error);
}

Result<std::unique_ptr<ReceivedStore>> ReceivedStore::Create(const Options& options) {
  if (options.root.empty()) return absl::InvalidArgumentError("the received store needs a folder");
  if (options.max_bytes < 1) {
    return absl::InvalidArgumentError("--dicom-store-bytes: must be positive");
  }
  std::error_code error;
  for (const char* sub : {"series", "index"}) {
    fs::create_directories(options.root / sub, error);
    if (error) {
      return absl::InvalidArgumentError(StrCat("the received DICOM store ", options.root.string(),
                                               ": cannot create: ", error.message()));
    }
  }
  ::chmod(options.root.c_str(), 0700);  // patients' images: the server's user only
  std::unique_ptr<ReceivedStore> store(new ReceivedStore(options));
  RETURN_IF_ERROR(store->Scan());
  return store;
}

Status ReceivedStore::Scan() {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(options_.root, error)) {
    if (entry.path().filename().string().starts_with(".tmp-")) fs::remove_all(entry.path(), error);
  }
  for (const auto& entry : fs::directory_iterator(options_.root / "index", error)) {
    std::ifstream file(entry.path());
    std::stringstream text;
    text << file.rdbuf();
    const json parsed = json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
    Result<ReceivedSeriesRecord> record = RecordFromJson(parsed);
    const std::string uid = entry.path().stem().string();
    if (!record.ok() || record->attributes.series_uid != uid ||
        !fs::is_directory(options_.root / "series" / uid)) {
      fs::remove(entry.path(), error);  // an entry without its series
      continue;
    }
    stored_bytes_ += record->bytes;
    series_[uid] = std::move(*record);
  }
  for (const auto& entry : fs::directory_iterator(options_.root / "series", error)) {
    if (!series_.contains(entry.path().filename().string())) {
      fs::remove_all(entry.path(), error);  // a commit cut short
    }
  }
  return absl::OkStatus();
}

Result<std::unique_ptr<ReceivedStore::Incoming>> ReceivedStore::BeginIncoming() const {
  std::string pattern = (options_.root / ".tmp-XXXXXX").string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    return absl::InternalError("the received DICOM store: cannot make a temporary folder");
  }
  return std::unique_ptr<Incoming>(new Incoming(pattern));
}

Status ReceivedStore::Reserve(int64_t bytes) {
  std::lock_guard lock(mutex_);
  if (stored_bytes_ + reserved_bytes_ + bytes > options_.max_bytes) {
    return absl::ResourceExhaustedError(StrCat("the received DICOM store is full (",
                                               options_.max_bytes, " bytes, --dicom-store-bytes)"));
  }
  reserved_bytes_ += bytes;
  return absl::OkStatus();
}

void ReceivedStore::Release(int64_t bytes) {
  std::lock_guard lock(mutex_);
  reserved_bytes_ = std::max<int64_t>(0, reserved_bytes_ - bytes);
}

Status ReceivedStore::WriteIndex(const ReceivedSeriesRecord& record) const {
  const fs::path final_path =
      options_.root / "index" / (record.attributes.series_uid + ".json");
  const fs::path temp_path = final_path.string() + ".tmp";
  {
    std::ofstream file(temp_path, std::ios::trunc);
    file << RecordToJson(record).dump(-1, ' ', false, json::error_handler_t::replace);
    if (!file.flush()) return absl::InternalError("the received DICOM store: cannot write its index");
  }
  ::chmod(temp_path.c_str(), 0600);
  std::error_code error;
  fs::rename(temp_path, final_path, error);
  if (error) return absl::InternalError("the received DICOM store: cannot write its index");
  return absl::OkStatus();
}

Result<int64_t> ReceivedStore::Commit(const SeriesFiles& s) {
  const std::string& uid = s.attributes.series_uid;
  RETURN_IF_ERROR(CheckUid(uid, "SeriesInstanceUID"));
  std::unique_lock files(files_mutex_);
  ReceivedSeriesRecord record;
  {
    std::lock_guard lock(mutex_);
    auto it = series_.find(uid);
    record = it != series_.end()
                 ? it->second
                 : ReceivedSeriesRecord{.attributes = s.attributes, .calling_ae = s.calling_ae};
  }
  const fs::path folder = options_.root / "series" / uid;
  std::error_code error;
  fs::create_directories(folder, error);
  std::set<std::string> have(record.sop_uids.begin(), record.sop_uids.end());
  int64_t added = 0, added_bytes = 0;
  for (const auto& [path, sop_uid] : s.files) {
    if (!have.insert(sop_uid).second) continue;  // sent again: kept once
    const fs::path target = folder / InstanceName(record.sop_uids.size() + 1);
    const int64_t size = static_cast<int64_t>(fs::file_size(path, error));
    if (error || MoveFile(path, target)) {
      return absl::InternalError(StrCat("the received DICOM store: cannot keep series ", uid));
    }
    record.sop_uids.push_back(sop_uid);
    added_bytes += size;
    ++added;
  }
  record.bytes += added_bytes;
  RETURN_IF_ERROR(WriteIndex(record));
  std::lock_guard lock(mutex_);
  reserved_bytes_ = std::max<int64_t>(0, reserved_bytes_ - s.bytes);
  stored_bytes_ += added_bytes;
  series_[uid] = std::move(record);
  return added;
}

StudySearch ReceivedStore::Search(const StudyQuery& query,
                                  const std::vector<std::string>& from) const {
  std::lock_guard lock(mutex_);
  std::map<std::string, StudySummary> studies;  // by study UID
  std::map<std::string, std::set<std::string>> modalities;
  for (const auto& [uid, r] : series_) {
    if (!FromAllowed(from, r.calling_ae) || !StudyMatches(query, r.attributes)) continue;
    const ReceivedInstance& a = r.attributes;
    auto [it, fresh] = studies.try_emplace(a.study_uid);
    StudySummary& s = it->second;
    if (fresh) {
      s = {.study_uid = a.study_uid, .patient_name = a.patient_name, .patient_id = a.patient_id,
           .patient_birth_date = a.patient_birth_date, .study_date = a.study_date,
           .study_description = a.study_description, .accession_number = a.accession_number,
           .series_count = 0, .instance_count = 0};
    }
    ++s.series_count;
    s.instance_count += static_cast<int64_t>(r.sop_uids.size());
    if (!a.modality.empty()) modalities[a.study_uid].insert(a.modality);
  }
  StudySearch out{.requests = 1};
  for (auto& [uid, s] : studies) {
    const std::set<std::string>& m = modalities[uid];
    if (!query.modality.empty() && !m.contains(query.modality)) continue;
    if (static_cast<int64_t>(out.studies.size()) == query.limit) {
      out.truncated = true;
      break;
    }
    s.modalities.assign(m.begin(), m.end());
    out.studies.push_back(std::move(s));
  }
  return out;
}

std::vector<SeriesSummary> ReceivedStore::ListSeries(const std::string& study_uid,
                                                     const std::vector<std::string>& from) const {
  std::lock_guard lock(mutex_);
  std::vector<SeriesSummary> out;
  for (const auto& [uid, r] : series_) {
    const ReceivedInstance& a = r.attributes;
    if (a.study_uid != study_uid || !FromAllowed(from, r.calling_ae)) continue;
    out.push_back({.series_uid = uid, .modality = a.modality,
                   .description = a.series_description, .body_part = a.body_part,
                   .series_number = a.series_number,
                   .instance_count = static_cast<int64_t>(r.sop_uids.size())});
  }
  std::stable_sort(out.begin(), out.end(), [](const SeriesSummary& x, const SeriesSummary& y) {
    return x.series_number < y.series_number;
  });
  return out;
}

Result<std::shared_ptr<ReceivedStore::Lease>> ReceivedStore::OpenSeries(
    const std::string& study_uid, const std::string& series_uid,
    const std::vector<std::string>& from) const {
  auto lease = std::make_shared<Lease>();
  lease->hold = std::shared_lock(files_mutex_);
  std::lock_guard lock(mutex_);
  auto it = series_.find(series_uid);
  if (it == series_.end() || it->second.attributes.study_uid != study_uid ||
      !FromAllowed(from, it->second.calling_ae)) {
    return absl::NotFoundError(
        StrCat("study ", study_uid, " holds no received series ", series_uid));
  }
  lease->folder = options_.root / "series" / series_uid;
  lease->instances = static_cast<int64_t>(it->second.sop_uids.size());
  return lease;
}

int64_t ReceivedStore::stored_bytes() const {
  std::lock_guard lock(mutex_);
  return stored_bytes_;
}

}  // namespace vpm::pacs

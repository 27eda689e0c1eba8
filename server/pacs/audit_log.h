// The audit log of PACS actions: one JSON object a line, appended and
// flushed per record, for whoever must answer "who looked at what".
// It names users, endpoints and DICOM UIDs, and never patient names, IDs
// or birth dates: a search records which filters were set, not their
// values.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <string>

#include "server/common/status.h"

namespace vpm::pacs {

struct AuditRecord {
  std::string user;
  std::string action;  // "search", "series", "thumbnail", "open", "export", "receive"
  std::string endpoint;
  std::string study_uid;  // empty when none
  std::string series_uid;
  Status result;           // its code is written ("OK", "PERMISSION_DENIED", ...)
  std::string filters;     // search: the filters set, "PatientName,StudyDate"
  int64_t matches = -1;    // search and series: how many answered; -1: not written
  std::string cache;       // open: "hit" or "miss"; thumbnail: "memory", "cache", "received", "pacs"
  int64_t instances = -1;  // open, export, receive: files of the series; -1: not written
  std::string calling_aet;  // receive: the node that sent the series
  int64_t refused = -1;     // receive: instances refused; -1: not written
};

class AuditLog {
 public:
  // Opens `path` for appending (created with mode 0600). InvalidArgument
  // naming the flag when it cannot.
  static Result<std::unique_ptr<AuditLog>> Open(const std::filesystem::path& path);

  // Appends {"time": "2026-01-02T03:04:05.678Z", "user": ..., "action": ...,
  // "endpoint": ..., "study_uid": ..., "series_uid": ..., "result": "OK",
  // "error": message (when not OK), ...} and flushes.
  void Record(const AuditRecord& record);

 private:
  explicit AuditLog(std::ofstream file) : file_(std::move(file)) {}
  std::mutex mutex_;
  std::ofstream file_;
};

}  // namespace vpm::pacs

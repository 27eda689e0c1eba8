#include "server/pacs/audit_log.h"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <ctime>
#include <memory>

#include <nlohmann/json.hpp>

namespace vpm::pacs {
namespace {

std::string UtcNow() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t seconds = std::chrono::system_clock::to_time_t(now);
  const int64_t ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::snprintf(text, sizeof(text), "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(ms));
  return text;
}

}  // namespace

Result<std::unique_ptr<AuditLog>> AuditLog::Open(const std::filesystem::path& path) {
  // Created private before the stream opens it.
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0600);
  if (fd < 0) {
    return absl::InvalidArgumentError(StrCat("--pacs-audit-log ", path.string(), ": cannot open"));
  }
  ::close(fd);
  std::ofstream file(path, std::ios::app);
  if (!file) {
    return absl::InvalidArgumentError(StrCat("--pacs-audit-log ", path.string(), ": cannot open"));
  }
  return std::unique_ptr<AuditLog>(new AuditLog(std::move(file)));
}

void AuditLog::Record(const AuditRecord& r) {
  nlohmann::json line = {{"time", UtcNow()},
                         {"user", r.user},
                         {"action", r.action},
                         {"endpoint", r.endpoint},
                         {"study_uid", r.study_uid},
                         {"series_uid", r.series_uid},
                         {"result", absl::StatusCodeToString(r.result.code())}};
  if (!r.result.ok()) line["error"] = std::string(r.result.message());
  if (!r.filters.empty()) line["filters"] = r.filters;
  if (r.matches >= 0) line["matches"] = r.matches;
  if (!r.cache.empty()) line["cache"] = r.cache;
  if (r.instances >= 0) line["instances"] = r.instances;
  if (!r.calling_aet.empty()) line["calling_aet"] = r.calling_aet;
  if (r.refused >= 0) line["refused"] = r.refused;
  const std::string text = line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::lock_guard lock(mutex_);
  file_ << text << '\n';
  file_.flush();
}

}  // namespace vpm::pacs

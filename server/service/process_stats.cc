#include "server/service/process_stats.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace vpm::service {

ProcessStats ReadProcessStats() {
  ProcessStats stats;
  {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
      if (line.starts_with("Threads:")) stats.threads = std::stoll(line.substr(8));
    }
  }
  std::error_code error;
  for (std::filesystem::directory_iterator it("/proc/self/fd", error), end; !error && it != end;
       it.increment(error)) {
    ++stats.open_fds;
  }
  // The iterator's own descriptor on /proc/self/fd was counted.
  if (stats.open_fds > 0) --stats.open_fds;
  {
    std::ifstream statm("/proc/self/statm");
    int64_t size_pages = 0, resident_pages = 0;
    if (statm >> size_pages >> resident_pages) {
      stats.resident_bytes = resident_pages * static_cast<int64_t>(sysconf(_SC_PAGESIZE));
    }
  }
  return stats;
}

}  // namespace vpm::service

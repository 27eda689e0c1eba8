// What this process holds, read from /proc/self (Linux): for the metrics a
// soak or a lifecycle test watches for leaks.
#pragma once

#include <cstdint>

namespace vpm::service {

struct ProcessStats {
  int64_t threads = 0;         // /proc/self/status Threads
  int64_t open_fds = 0;        // entries of /proc/self/fd
  int64_t resident_bytes = 0;  // /proc/self/statm resident pages * page size
};

// Fields that cannot be read stay 0.
ProcessStats ReadProcessStats();

}  // namespace vpm::service

#include "server/gpu/dispatch_threads.h"

#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cstring>

namespace vpm::gpu {

namespace {

constexpr long kMaxThreads = 32;  // llvmpipe's LP_MAX_THREADS

}  // namespace

uint32_t DispatchThreads(bool cpu_device) {
  if (!cpu_device) return 1;
  long threads = sysconf(_SC_NPROCESSORS_ONLN);
  if (const char* env = std::getenv("LP_NUM_THREADS")) {
    long value = 0;
    const char* end = env + std::strlen(env);
    const auto [ptr, ec] = std::from_chars(env, end, value);
    if (ec == std::errc() && ptr == end) threads = value;
  }
  return uint32_t(std::clamp(threads, 1L, kMaxThreads));
}

}  // namespace vpm::gpu

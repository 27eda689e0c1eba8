#include "server/common/random_hex.h"

#include <sys/random.h>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <vector>

namespace vpm {

std::string RandomHex(size_t bytes) {
  std::vector<uint8_t> random(bytes);
  for (size_t done = 0; done < bytes;) {
    const ssize_t got = getrandom(random.data() + done, bytes - done, 0);
    if (got < 0 && errno == EINTR) continue;
    // getrandom fails only for bad arguments or a kernel without it (< 3.17):
    // an id that could be guessed is worse than no server.
    if (got <= 0) std::abort();
    done += static_cast<size_t>(got);
  }
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * bytes);
  for (const uint8_t b : random) {
    hex += kDigits[b >> 4];
    hex += kDigits[b & 15];
  }
  return hex;
}

}  // namespace vpm

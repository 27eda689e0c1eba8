#include "client/common/session_key.h"

#include <pwd.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <span>

#include "server/common/sha256.h"

namespace vpm::cli {

std::string DefaultSessionKey() {
  if (const char* key = std::getenv("VPM_SESSION_KEY"); key != nullptr && *key != '\0') return key;
  std::string user;
  if (const char* name = std::getenv("USER"); name != nullptr && *name != '\0') {
    user = name;
  } else if (const passwd* entry = getpwuid(getuid()); entry != nullptr) {
    user = entry->pw_name;
  } else {
    user = std::to_string(getuid());
  }
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  const std::string who = user + "@" + host;
  Sha256 sha;
  sha.Update(std::span(reinterpret_cast<const uint8_t*>(who.data()), who.size()));
  return "user-" + sha.FinishHex().substr(0, 16);
}

}  // namespace vpm::cli

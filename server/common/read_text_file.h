// A small text file (PEM certificates, keys) read whole. InvalidArgument
// names the flag it came from: "--tls-cert server.pem: cannot read".
#pragma once

#include <fstream>
#include <sstream>
#include <string>

#include "server/common/status.h"

namespace vpm {

inline Result<std::string> ReadTextFile(const std::string& path, const char* flag) {
  std::ifstream file(path);
  if (!file) return absl::InvalidArgumentError(StrCat(flag, " ", path, ": cannot read"));
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

}  // namespace vpm

// How every vpm command ends: an error as a value becomes one line on stderr
// ("vpm: <code>: <message>") and a non-zero exit status.
#pragma once

#include <iostream>

#include "server/common/status.h"

namespace vpm::cli {

inline int ExitWith(const Status& status) {
  if (status.ok()) return 0;
  std::cerr << "vpm: " << absl::StatusCodeToString(status.code()) << ": " << status.message()
            << "\n";
  return status.code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
}

}  // namespace vpm::cli

// Adds context (usually a file name) in front of an error message, keeping
// its code: "brain.nii: header says ...".
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm {

inline Status PrefixStatus(const Status& status, std::string_view prefix) {
  if (status.ok()) return status;
  return Status(status.code(), StrCat(std::string(prefix), ": ", status.message()));
}

}  // namespace vpm

// Where LoadVolume may read: a relative path under the data root, with no
// ".." component and no symlink leading outside it.
#pragma once

#include <filesystem>
#include <string_view>

#include "server/common/status.h"

namespace vpm::service {

// data_root   the server's --data-root (empty: file loads are off)
// relative    the client's path
// Returns the canonical path of an existing file or folder inside the root.
// Errors: FailedPrecondition without a data root; InvalidArgument for an
// empty or absolute path or one with a ".." component; PermissionDenied when
// it resolves (through symlinks) outside the root; NotFound when missing.
Result<std::filesystem::path> ResolveDataPath(const std::filesystem::path& data_root,
                                              std::string_view relative);

}  // namespace vpm::service

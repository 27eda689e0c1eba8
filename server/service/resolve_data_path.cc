#include "server/service/resolve_data_path.h"

#include <algorithm>

namespace vpm::service {

namespace fs = std::filesystem;

Result<fs::path> ResolveDataPath(const fs::path& data_root, std::string_view relative) {
  if (data_root.empty()) {
    return absl::FailedPreconditionError("source: the server has no --data-root; file loads are off");
  }
  if (relative.empty()) return absl::InvalidArgumentError("source: empty path");
  const fs::path rel{std::string(relative)};
  if (rel.is_absolute()) {
    return absl::InvalidArgumentError(
        StrCat("source: '", relative, "' is absolute; give a path relative to the data root"));
  }
  for (const fs::path& part : rel) {
    if (part == "..") {
      return absl::InvalidArgumentError(StrCat("source: '", relative, "' has a '..' component"));
    }
  }
  std::error_code error;
  const fs::path root = fs::canonical(data_root, error);
  if (error) {
    return absl::FailedPreconditionError(
        StrCat("data root ", data_root.string(), ": ", error.message()));
  }
  const fs::path joined = root / rel;
  if (!fs::exists(fs::symlink_status(joined, error)) && !fs::exists(joined, error)) {
    return absl::NotFoundError(StrCat("source: '", relative, "' is not in the data root"));
  }
  const fs::path real = fs::canonical(joined, error);
  if (error) {
    // A dangling symlink or an unreadable component: say as little as for a
    // missing file, but never follow it.
    return absl::NotFoundError(StrCat("source: '", relative, "': ", error.message()));
  }
  auto [root_end, real_it] = std::mismatch(root.begin(), root.end(), real.begin(), real.end());
  if (root_end != root.end()) {
    return absl::PermissionDeniedError(
        StrCat("source: '", relative, "' resolves outside the data root"));
  }
  return real;
}

}  // namespace vpm::service

#include "server/service/resolve_data_path.h"

#include <algorithm>

#include "server/common/path_inside.h"

namespace vpm::service {

namespace fs = std::filesystem;

namespace {

// The client's path in a message: at most 200 bytes of it.
std::string Quoted(std::string_view path) {
  constexpr size_t kShown = 200;
  if (path.size() <= kShown) return StrCat("'", path, "'");
  return StrCat("'", path.substr(0, kShown), "...' (", path.size(), " bytes)");
}

Status CheckPathShape(std::string_view relative) {
  if (relative.empty()) return absl::InvalidArgumentError("source: empty path");
  if (relative.size() > kMaxSourcePathBytes) {
    return absl::InvalidArgumentError(StrCat("source: a path of ", relative.size(),
                                             " bytes; at most ", kMaxSourcePathBytes));
  }
  const fs::path rel{std::string(relative)};
  if (rel.is_absolute()) {
    return absl::InvalidArgumentError(StrCat(
        "source: ", Quoted(relative), " is absolute; give a path relative to the data root"));
  }
  for (const fs::path& part : rel) {
    if (part == "..") {
      return absl::InvalidArgumentError(
          StrCat("source: ", Quoted(relative), " has a '..' component"));
    }
    if (part.native().size() > kMaxPathComponentBytes) {
      return absl::InvalidArgumentError(StrCat("source: a path component of ",
                                               part.native().size(), " bytes; at most ",
                                               kMaxPathComponentBytes));
    }
  }
  return absl::OkStatus();
}

}  // namespace

Result<fs::path> CanonicalDataRoot(const fs::path& data_root) {
  if (data_root.empty()) {
    return absl::FailedPreconditionError("source: the server has no --data-root; file loads are off");
  }
  std::error_code error;
  fs::path root = fs::canonical(data_root, error);
  if (error) {
    return absl::FailedPreconditionError(
        StrCat("the server's data root is unavailable: ", error.message()));
  }
  return root;
}

Result<fs::path> ResolveDataPath(const fs::path& data_root, std::string_view relative) {
  ASSIGN_OR_RETURN(const fs::path root, CanonicalDataRoot(data_root));
  RETURN_IF_ERROR(CheckPathShape(relative));
  const fs::path joined = root / fs::path(std::string(relative));
  std::error_code error;
  if (!fs::exists(fs::symlink_status(joined, error)) && !fs::exists(joined, error)) {
    return absl::NotFoundError(StrCat("source: ", Quoted(relative), " is not in the data root"));
  }
  const fs::path real = fs::canonical(joined, error);
  if (error == std::errc::filename_too_long) {
    return absl::InvalidArgumentError(StrCat("source: ", Quoted(relative), ": name too long"));
  }
  if (error) {
    // A dangling symlink or an unreadable component: say as little as for a
    // missing file, but never follow it.
    return absl::NotFoundError(StrCat("source: ", Quoted(relative), ": ", error.message()));
  }
  if (!PathIsInside(root, real)) {
    return absl::PermissionDeniedError(
        StrCat("source: ", Quoted(relative), " resolves outside the data root"));
  }
  return real;
}

Result<std::string> ResolveDataSource(const fs::path& data_root, std::string_view source) {
  const size_t query = source.rfind('?');
  if (query == std::string_view::npos) {
    ASSIGN_OR_RETURN(const fs::path path, ResolveDataPath(data_root, source));
    return path.string();
  }
  // A file may have '?' in its name: the whole string first.
  Result<fs::path> whole = ResolveDataPath(data_root, source);
  if (whole.ok() || !absl::IsNotFound(whole.status())) {
    RETURN_IF_ERROR(whole.status());
    return whole->string();
  }
  ASSIGN_OR_RETURN(const fs::path folder, ResolveDataPath(data_root, source.substr(0, query)));
  return StrCat(folder.string(), source.substr(query));
}

Status HideFolder(const Status& status, const fs::path& folder, std::string_view shown_as) {
  if (status.ok() || folder.empty()) return status;
  std::string message(status.message());
  const std::string name = folder.string();
  const std::string with_slash = name.ends_with('/') ? name : name + "/";
  for (const auto& [from, to] : {std::pair{with_slash, std::string()},
                                 std::pair{name, std::string(shown_as)}}) {
    for (size_t at = message.find(from); at != std::string::npos;
         at = message.find(from, at + to.size())) {
      message.replace(at, from.size(), to);
    }
  }
  return Status(status.code(), message);
}

}  // namespace vpm::service

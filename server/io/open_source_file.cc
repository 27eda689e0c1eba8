#include "server/io/open_source_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <memory>

#include "server/common/path_inside.h"

namespace vpm {
namespace {

Status OpenError(const std::string& name, int error) {
  switch (error) {
    case ENOENT:
    case ENOTDIR:
      return absl::NotFoundError(StrCat(name, ": no such file"));
    case EACCES:
    case EPERM:
      return absl::PermissionDeniedError(StrCat(name, ": not readable"));
    case ELOOP:
      return absl::InvalidArgumentError(StrCat(name, ": a symbolic link (loop or swapped in)"));
    case ENAMETOOLONG:
      return absl::InvalidArgumentError(StrCat(name, ": name too long"));
    case ENXIO:  // a FIFO without a writer, a socket: O_NONBLOCK says so at once
      return absl::InvalidArgumentError(StrCat(name, ": not a regular file"));
    default:
      return absl::InternalError(StrCat(name, ": cannot open: ", std::strerror(error)));
  }
}

const char* KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  return "a special file";
}

// The path to open: `path` itself, or, under a read root, its fully resolved
// form once it is known to lie inside the root.
Result<std::filesystem::path> PathToOpen(const std::filesystem::path& path,
                                         const VolumeLimits& limits) {
  if (limits.read_root.empty()) return path;
  std::unique_ptr<char, decltype(&std::free)> real(realpath(path.c_str(), nullptr), &std::free);
  if (real == nullptr) return OpenError(path.string(), errno);
  std::filesystem::path resolved(real.get());
  if (!PathIsInside(limits.read_root, resolved)) {
    return absl::PermissionDeniedError(
        StrCat(path.string(), ": resolves outside the data root"));
  }
  return resolved;
}

}  // namespace

SourceFile::~SourceFile() {
  if (fd_ >= 0) ::close(fd_);
}

Result<SourceFile> OpenSourceFile(const std::filesystem::path& path, const VolumeLimits& limits) {
  const std::string name = path.string();
  ASSIGN_OR_RETURN(const std::filesystem::path target, PathToOpen(path, limits));
  // O_NONBLOCK: opening a FIFO without a writer would otherwise wait for one.
  int flags = O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
  if (!limits.read_root.empty()) flags |= O_NOFOLLOW;
  const int fd = ::open(target.c_str(), flags);
  if (fd < 0) return OpenError(name, errno);
  SourceFile file(fd, 0);
  struct stat info {};
  if (::fstat(fd, &info) != 0) return OpenError(name, errno);
  if (!S_ISREG(info.st_mode)) {
    return absl::InvalidArgumentError(
        StrCat(name, ": ", KindOf(info.st_mode), ", not a regular file"));
  }
  // Reads of a regular file do not block; clear the flag all the same.
  const int status_flags = ::fcntl(fd, F_GETFL);
  if (status_flags >= 0) ::fcntl(fd, F_SETFL, status_flags & ~O_NONBLOCK);
  return SourceFile(file.release(), static_cast<int64_t>(info.st_size));
}

}  // namespace vpm

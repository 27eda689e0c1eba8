#include "server/common/write_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace vpm {
namespace {

Status WriteError(const std::filesystem::path& path, int error) {
  const std::string reason = std::strerror(error);
  const std::string message = StrCat(path.string(), ": cannot write: ", reason);
  if (error == EACCES || error == EPERM || error == EROFS) {
    return absl::PermissionDeniedError(message);
  }
  if (error == ENOENT || error == ENOTDIR) return absl::NotFoundError(message);
  // No room on the disk, over the quota, or over the process's file size
  // limit: the machine's shortage, not a fault of the bytes.
  if (error == ENOSPC || error == EDQUOT || error == EFBIG) {
    return absl::ResourceExhaustedError(message);
  }
  return absl::InternalError(message);
}

}  // namespace

Status WriteFile(const std::filesystem::path& path, std::string_view bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return WriteError(path, errno);
  errno = 0;
  const size_t written = bytes.empty() ? 0 : std::fwrite(bytes.data(), 1, bytes.size(), file);
  const int write_error = written == bytes.size() ? 0 : (errno != 0 ? errno : EIO);
  const int close_error = std::fclose(file) == 0 ? 0 : errno;
  if (write_error != 0) return WriteError(path, write_error);
  if (close_error != 0) return WriteError(path, close_error);
  return absl::OkStatus();
}

Status MakeDirectories(const std::filesystem::path& dir) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) {
    return absl::FailedPreconditionError(
        StrCat(dir.string(), ": cannot create the folder: ", error.message()));
  }
  return absl::OkStatus();
}

}  // namespace vpm

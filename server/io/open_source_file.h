// Opening a file that a reader reads on someone's behalf. The one place where
// server/io opens a source file: ReadFileBytes, ReadFileRangeInto and
// ReadFilePrefix (and so every reader, DICOM folder members and detached
// data files included) go through it.
//
// Only a regular file is opened, without blocking: a FIFO, a device or a
// socket is refused at once instead of hanging the reading thread. When
// `limits.read_root` is set (the server's --data-root, or an upload's
// private folder), the path is first resolved through every symlink and must
// lie inside that root; the resolved path is then opened with O_NOFOLLOW, so
// a link swapped in at the last component after the check is refused too.
#pragma once

#include <cstdint>
#include <filesystem>
#include <utility>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// An open, read-only descriptor of a regular file; closed on destruction.
class SourceFile {
 public:
  SourceFile(int fd, int64_t size_bytes) : fd_(fd), size_bytes_(size_bytes) {}
  SourceFile(SourceFile&& other) noexcept
      : fd_(std::exchange(other.fd_, -1)), size_bytes_(other.size_bytes_) {}
  SourceFile& operator=(SourceFile&&) = delete;
  SourceFile(const SourceFile&) = delete;
  ~SourceFile();

  int fd() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }  // the caller closes it
  int64_t size_bytes() const { return size_bytes_; }  // from fstat at open

 private:
  int fd_ = -1;
  int64_t size_bytes_ = 0;
};

// path     the file as the reader names it (absolute, or relative to the
//          working directory)
// limits   read_root: empty, or the folder the file must resolve inside
// Errors (messages start with `path`): NotFound when it does not exist;
// PermissionDenied when it resolves outside limits.read_root or cannot be
// read; InvalidArgument when it is not a regular file (a folder, FIFO,
// device or socket) or its name is too long.
Result<SourceFile> OpenSourceFile(const std::filesystem::path& path, const VolumeLimits& limits);

}  // namespace vpm

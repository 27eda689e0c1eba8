// A zip (or tar, plain or gzip) archive of DICOM files unpacked into a
// folder (libarchive), for a DICOM series uploaded as one file. Entries are
// written under names of our own (000001, 000002, ...), never the paths the
// archive gives, so an entry cannot escape the folder; directories,
// symlinks, hard links and devices are skipped.
#pragma once

#include <cstdint>
#include <filesystem>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/io/open_source_file.h"

namespace vpm {

struct ArchiveLimits {
  int64_t max_bytes = int64_t{4} << 30;  // unpacked, all entries together
  int64_t max_entries = 100000;          // regular files
};

// Unpacks `archive` (opened by OpenSourceFile: a regular file, inside the
// read root) into `folder` (an existing, empty, private folder).
// Returns the number of files written. Errors (messages without the
// folder's path): InvalidArgument for a file that is not an archive libarchive
// reads, a damaged or truncated one, encrypted entries, or no file in it;
// ResourceExhausted past `limits` (an archive bomb stops at the cap);
// Internal when a file cannot be written; `cancel`'s status.
Result<int64_t> ExtractArchive(const SourceFile& archive, const std::filesystem::path& folder,
                               const ArchiveLimits& limits, const CancelToken& cancel = {});

}  // namespace vpm

#include "server/io/extract_archive.h"

#include <archive.h>
#include <archive_entry.h>

#include <cstdio>
#include <fstream>
#include <memory>

namespace vpm {
namespace {

struct ArchiveDeleter {
  void operator()(archive* a) const { archive_read_free(a); }
};

std::string Why(archive* a) {
  const char* text = archive_error_string(a);
  return text != nullptr ? std::string(text).substr(0, 200) : std::string("unknown error");
}

// Copies the current entry's data to `out`, counting into `*total`.
Status CopyEntry(archive* a, std::ofstream& out, int64_t* total, const ArchiveLimits& limits,
                 const CancelToken& cancel) {
  char buffer[1 << 16];
  for (;;) {
    RETURN_IF_ERROR(cancel.Check());
    const la_ssize_t n = archive_read_data(a, buffer, sizeof buffer);
    if (n == 0) return absl::OkStatus();
    if (n < 0) return absl::InvalidArgumentError(StrCat("a damaged archive entry (", Why(a), ")"));
    *total += n;
    if (*total > limits.max_bytes) {
      return absl::ResourceExhaustedError(
          StrCat("the archive unpacks to over ", limits.max_bytes, " bytes (--max-upload-bytes)"));
    }
    out.write(buffer, n);
    if (!out) return absl::InternalError("cannot write an unpacked file");
  }
}

}  // namespace

Result<int64_t> ExtractArchive(const SourceFile& archive_file, const std::filesystem::path& folder,
                               const ArchiveLimits& limits, const CancelToken& cancel) {
  std::unique_ptr<archive, ArchiveDeleter> a(archive_read_new());
  if (!a) return absl::InternalError("libarchive: cannot make a reader");
  archive_read_support_format_zip(a.get());
  archive_read_support_format_tar(a.get());
  archive_read_support_filter_gzip(a.get());
  archive_read_support_filter_none(a.get());
  if (archive_read_open_fd(a.get(), archive_file.fd(), 1 << 16) != ARCHIVE_OK) {
    return absl::InvalidArgumentError(
        StrCat("not a zip or tar archive (", Why(a.get()), ")"));
  }
  int64_t files = 0, total = 0;
  for (;;) {
    RETURN_IF_ERROR(cancel.Check());
    archive_entry* entry = nullptr;
    const int r = archive_read_next_header(a.get(), &entry);
    if (r == ARCHIVE_EOF) break;
    if (r != ARCHIVE_OK && r != ARCHIVE_WARN) {
      return absl::InvalidArgumentError(StrCat("a damaged or truncated archive (", Why(a.get()), ")"));
    }
    if (archive_entry_filetype(entry) != AE_IFREG || archive_entry_hardlink(entry) != nullptr) {
      continue;  // directories, links, devices
    }
    if (archive_entry_is_encrypted(entry)) {
      return absl::InvalidArgumentError("the archive holds encrypted entries; upload it unencrypted");
    }
    if (++files > limits.max_entries) {
      return absl::ResourceExhaustedError(
          StrCat("the archive holds over ", limits.max_entries, " files"));
    }
    char name[32];
    std::snprintf(name, sizeof name, "%06lld", static_cast<long long>(files));
    std::ofstream out(folder / name, std::ios::binary | std::ios::trunc);
    if (!out) return absl::InternalError("cannot create an unpacked file");
    RETURN_IF_ERROR(CopyEntry(a.get(), out, &total, limits, cancel));
  }
  if (files == 0) return absl::InvalidArgumentError("the archive holds no file");
  return files;
}

}  // namespace vpm

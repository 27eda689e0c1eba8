// Uploaded volumes kept on disk for their cases, content-addressed: a file
// is stored once under its SHA-256 (DIR/blobs/SHA256/NAME, NAME the
// uploaded file's name, whose extension picks the reader), so a case of an
// upload reopens after a restart (docs/CASES.md). Files are written to a
// temporary name and renamed into place: a crash leaves no half file under
// a hash. Thread-safe (the file system's rename is the only shared step).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::cases {

class BlobStore {
 public:
  // Creates DIR/blobs when missing.
  static Result<BlobStore> Open(const std::filesystem::path& dir);

  // Copies `file` in as (sha256_hex, name) unless it is there already.
  // InvalidArgument for a malformed hash or name; ResourceExhausted when the
  // disk is full (nothing is left behind).
  Status Put(std::string_view sha256_hex, std::string_view name,
             const std::filesystem::path& file) const;
  // Removes the stored file (and its hash's folder once empty); OK when it
  // was not there.
  Status Remove(std::string_view sha256_hex, std::string_view name) const;
  // The stored file, if any.
  std::optional<std::filesystem::path> Find(std::string_view sha256_hex,
                                            std::string_view name) const;
  // The reference a case keeps: "upload:SHA256/NAME"; and back (nullopt for
  // anything else).
  static std::string Reference(std::string_view sha256_hex, std::string_view name);
  static std::optional<std::pair<std::string, std::string>> ParseReference(std::string_view ref);

 private:
  explicit BlobStore(std::filesystem::path root) : root_(std::move(root)) {}
  std::filesystem::path root_;  // DIR/blobs
};

}  // namespace vpm::cases

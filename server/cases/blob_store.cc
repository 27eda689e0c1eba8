#include "server/cases/blob_store.h"

#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstring>

namespace vpm::cases {
namespace {

namespace fs = std::filesystem;

bool IsSha256Hex(std::string_view s) {
  if (s.size() != 64) return false;
  for (char c : s) {
    if (!std::isdigit(static_cast<unsigned char>(c)) && (c < 'a' || c > 'f')) return false;
  }
  return true;
}

// A plain file name: no folder, no dot-only name, no control characters.
bool IsPlainName(std::string_view name) {
  if (name.empty() || name.size() > 255 || name == "." || name == "..") return false;
  for (char c : name) {
    if (c == '/' || c == '\0' || static_cast<unsigned char>(c) < 0x20) return false;
  }
  return true;
}

Status CheckKey(std::string_view sha256_hex, std::string_view name) {
  if (!IsSha256Hex(sha256_hex)) {
    return absl::InvalidArgumentError("blob store: not a lowercase SHA-256 (64 hex digits)");
  }
  if (!IsPlainName(name)) return absl::InvalidArgumentError("blob store: not a plain file name");
  return absl::OkStatus();
}

}  // namespace

Result<BlobStore> BlobStore::Open(const fs::path& dir) {
  std::error_code error;
  fs::create_directories(dir / "blobs", error);
  if (error) {
    return absl::FailedPreconditionError(
        StrCat("blob store: cannot create ", (dir / "blobs").string(), " (", error.message(), ")"));
  }
  return BlobStore(dir / "blobs");
}

Status BlobStore::Put(std::string_view sha256_hex, std::string_view name,
                      const fs::path& file) const {
  RETURN_IF_ERROR(CheckKey(sha256_hex, name));
  if (Find(sha256_hex, name)) return absl::OkStatus();
  const fs::path folder = root_ / std::string(sha256_hex);
  const fs::path target = folder / std::string(name);
  const fs::path temporary =
      folder / StrCat(".incoming-", ::getpid(), "-", std::hash<std::string>{}(file.string()));
  std::error_code error;
  fs::create_directories(folder, error);
  if (!error) fs::copy_file(file, temporary, fs::copy_options::overwrite_existing, error);
  if (!error) fs::rename(temporary, target, error);
  if (!error) return absl::OkStatus();
  fs::remove(temporary, error);
  const std::string why = StrCat("blob store: could not keep the upload (", error.message(), ")");
  if (error.value() == ENOSPC || error.value() == EDQUOT || error.value() == EFBIG) {
    return absl::ResourceExhaustedError(why);
  }
  return absl::InternalError(why);
}

Status BlobStore::Remove(std::string_view sha256_hex, std::string_view name) const {
  RETURN_IF_ERROR(CheckKey(sha256_hex, name));
  const fs::path folder = root_ / std::string(sha256_hex);
  std::error_code error;
  fs::remove(folder / std::string(name), error);
  if (error) {
    return absl::InternalError(
        StrCat("blob store: could not remove a kept upload (", error.message(), ")"));
  }
  fs::remove(folder, error);  // only when empty: another name of the same bytes stays
  return absl::OkStatus();
}

std::optional<fs::path> BlobStore::Find(std::string_view sha256_hex, std::string_view name) const {
  if (!CheckKey(sha256_hex, name).ok()) return std::nullopt;
  const fs::path target = root_ / std::string(sha256_hex) / std::string(name);
  std::error_code error;
  if (!fs::is_regular_file(fs::symlink_status(target, error))) return std::nullopt;
  return target;
}

std::string BlobStore::Reference(std::string_view sha256_hex, std::string_view name) {
  return StrCat("upload:", sha256_hex, "/", name);
}

std::optional<std::pair<std::string, std::string>> BlobStore::ParseReference(
    std::string_view ref) {
  constexpr std::string_view kPrefix = "upload:";
  if (!ref.starts_with(kPrefix)) return std::nullopt;
  ref.remove_prefix(kPrefix.size());
  const size_t slash = ref.find('/');
  if (slash == std::string_view::npos) return std::nullopt;
  std::string sha(ref.substr(0, slash)), name(ref.substr(slash + 1));
  if (!CheckKey(sha, name).ok()) return std::nullopt;
  return std::make_pair(std::move(sha), std::move(name));
}

}  // namespace vpm::cases

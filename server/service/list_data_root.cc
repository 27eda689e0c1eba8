#include "server/service/list_data_root.h"

#include <dirent.h>
#include <sys/stat.h>

#include <algorithm>
#include <memory>

#include "server/io/read_dicom_slice.h"
#include "server/io/read_file_bytes.h"
#include "server/io/read_volume.h"
#include "server/service/resolve_data_path.h"
#include "server/common/path_inside.h"

namespace vpm::service {
namespace {

namespace fs = std::filesystem;

// What ReadVolume makes of a file of this name (server/io/read_volume.h).
DataRootKind FileKind(const std::string& name) {
  if (IsVolumeFileName(name)) return DataRootKind::kVolumeFile;
  if (IsArchiveName(name)) return DataRootKind::kArchive;
  return DataRootKind::kOtherFile;
}

// Printable UTF-8 (a protobuf string must be UTF-8; a control character
// would garble a terminal), not hidden.
bool ShownName(std::string_view name) {
  if (name.empty() || name[0] == '.' || name.size() > 255) return false;
  for (size_t i = 0; i < name.size();) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (c < 0x20 || c == 0x7f || c == 0xc0 || c == 0xc1 || c > 0xf4) return false;
    const size_t extra = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2
                       : (c & 0xf8) == 0xf0 ? 3 : 9;
    if (extra == 9 || i + extra >= name.size() + (extra == 0 ? 1 : 0)) return false;
    for (size_t k = 1; k <= extra; ++k) {
      if ((static_cast<unsigned char>(name[i + k]) & 0xc0) != 0x80) return false;
    }
    if (c == 0xed && static_cast<unsigned char>(name[i + 1]) >= 0xa0) return false;  // surrogates
    i += extra + 1;
  }
  return true;
}

// Whether one of the first 16 regular files of `folder` is DICOM Part 10.
bool HoldsDicom(const fs::path& folder, const fs::path& root) {
  const VolumeLimits limits{.read_root = root};
  std::error_code error;
  int looked = 0;
  for (fs::directory_iterator it(folder, error), end; !error && it != end && looked < 16;
       it.increment(error)) {
    if (!it->is_regular_file(error) || it->path().filename().native().starts_with('.')) continue;
    ++looked;
    Result<std::vector<uint8_t>> head = ReadFilePrefix(it->path(), 132 + 4, limits);
    if (head.ok() && LooksLikeDicom(*head)) return true;
  }
  return false;
}

// The entry `name` of `folder` (`relative` to the root).
DataRootEntry Describe(const fs::path& folder, const std::string& relative,
                       const std::string& name, const fs::path& root) {
  DataRootEntry entry{.name = name, .kind = DataRootKind::kNotOpenable};
  const fs::path path = folder / name;
  struct stat own {};
  if (::lstat(path.c_str(), &own) != 0) return entry;
  entry.modified_unix_ms = int64_t{own.st_mtim.tv_sec} * 1000 + own.st_mtim.tv_nsec / 1000000;
  struct stat target = own;
  if (S_ISLNK(own.st_mode)) {
    std::error_code error;
    const fs::path real = fs::canonical(path, error);
    if (error || !PathIsInside(root, real) || ::stat(real.c_str(), &target) != 0) return entry;
  }
  const std::string source = relative.empty() ? name : relative + "/" + name;
  const bool loadable_name = name.find('?') == std::string::npos;  // '?' starts a query
  if (S_ISDIR(target.st_mode)) {
    entry.kind = HoldsDicom(path, root) ? DataRootKind::kDicomFolder : DataRootKind::kFolder;
    if (entry.kind == DataRootKind::kDicomFolder && loadable_name) entry.source = source;
  } else if (S_ISREG(target.st_mode)) {
    entry.kind = FileKind(name);
    entry.size_bytes = int64_t{target.st_size};
    if (entry.kind != DataRootKind::kOtherFile && loadable_name) entry.source = source;
  }
  return entry;
}

}  // namespace

Result<DataRootListing> ListDataRoot(const fs::path& data_root, std::string_view relative,
                                     size_t max_entries) {
  ASSIGN_OR_RETURN(const fs::path root, CanonicalDataRoot(data_root));
  while (!relative.empty() && relative.back() == '/') relative.remove_suffix(1);
  fs::path folder = root;
  if (!relative.empty() && relative != ".") {
    ASSIGN_OR_RETURN(folder, ResolveDataPath(root, relative));
  }
  std::error_code error;
  if (!fs::is_directory(folder, error)) {
    return absl::InvalidArgumentError(StrCat("path: '", relative.substr(0, 200),
                                             "' is not a folder of the data root"));
  }
  DataRootListing out;
  out.path = folder == root ? "" : folder.lexically_relative(root).string();
  std::unique_ptr<DIR, int (*)(DIR*)> dir(::opendir(folder.c_str()), ::closedir);
  if (!dir) return absl::PermissionDeniedError("path: the folder cannot be read");
  std::vector<std::string> names;
  const size_t max_read = max_entries * 20;
  size_t read = 0;
  while (const dirent* d = ::readdir(dir.get())) {
    if (++read > max_read) {
      out.truncated = true;
      break;
    }
    if (ShownName(d->d_name)) names.emplace_back(d->d_name);
  }
  std::sort(names.begin(), names.end());
  if (names.size() > max_entries) {  // the first by name; only those are looked into
    names.resize(max_entries);
    out.truncated = true;
  }
  for (const std::string& name : names) out.entries.push_back(Describe(folder, out.path, name, root));
  const auto is_folder = [](const DataRootEntry& e) {
    return e.kind == DataRootKind::kFolder || e.kind == DataRootKind::kDicomFolder;
  };
  std::stable_partition(out.entries.begin(), out.entries.end(), is_folder);
  return out;
}

}  // namespace vpm::service

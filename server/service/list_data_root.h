// One folder of the server's --data-root as the "Server files" browser
// shows it (ListDataRoot): its entries with what each is, within the same
// jail as LoadVolume (resolve_data_path.h). Messages never name the root.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"

namespace vpm::service {

enum class DataRootKind {
  kFolder,       // a folder without DICOM files among its first 16 files
  kVolumeFile,   // .nii .nii.gz .nrrd .nhdr .mha .mhd
  kDicomFolder,  // a folder holding DICOM Part 10 files: LoadVolume reads it as a series
  kArchive,      // .zip .tar .tar.gz .tgz: LoadVolume reads the DICOM series in it
  kOtherFile,    // a regular file vpm does not open by itself
  kNotOpenable,  // a FIFO, socket or device, or a symlink leading outside the root or nowhere
};

struct DataRootEntry {
  std::string name;  // valid UTF-8 without control characters, at most 255 bytes
  DataRootKind kind = DataRootKind::kOtherFile;
  int64_t size_bytes = 0;        // regular files; 0 otherwise
  int64_t modified_unix_ms = 0;  // of the entry itself (lstat), ms since 1970
  // The LoadVolume source that opens it, relative to the root; "" for
  // folders without DICOM, other files and what cannot be opened.
  std::string source;
};

struct DataRootListing {
  std::string path;  // the folder listed, relative to the root ("" for the root)
  std::vector<DataRootEntry> entries;  // folders first, then by name
  bool truncated = false;              // more entries than max_entries
};

inline constexpr size_t kMaxDataRootEntries = 1000;

// data_root    the server's --data-root (empty: FailedPrecondition)
// relative     the folder to list, relative to the root; "" the root itself
// max_entries  the most entries returned; names starting with '.' and names
//              that are not printable UTF-8 are left out
// Errors: those of ResolveDataPath (InvalidArgument for an absolute path or
// a ".." component, PermissionDenied for a symlink escape, NotFound), and
// InvalidArgument when the path is not a folder. At most 20 x max_entries
// names are read from the folder.
Result<DataRootListing> ListDataRoot(const std::filesystem::path& data_root,
                                     std::string_view relative,
                                     size_t max_entries = kMaxDataRootEntries);

}  // namespace vpm::service

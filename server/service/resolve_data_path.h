// Where LoadVolume may read: a relative path under the data root, with no
// ".." component and no symlink leading outside it. The files a reader then
// opens (DICOM folder members, detached data files) are held to the same
// root by server/io/open_source_file.h, through VolumeLimits::read_root.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::service {

// The longest source path a client may name, bytes, and the longest
// component (Linux's NAME_MAX): longer ones are InvalidArgument before any
// system call sees them.
inline constexpr size_t kMaxSourcePathBytes = 4096;
inline constexpr size_t kMaxPathComponentBytes = 255;

// data_root   the server's --data-root (empty: file loads are off)
// Returns its canonical form. FailedPrecondition without a data root or when
// it cannot be resolved (the message does not name it).
Result<std::filesystem::path> CanonicalDataRoot(const std::filesystem::path& data_root);

// data_root   the server's --data-root (empty: file loads are off)
// relative    the client's path
// Returns the canonical path of an existing file or folder inside the root.
// Errors: FailedPrecondition without a data root; InvalidArgument for an
// empty, absolute or too long path or one with a ".." component;
// PermissionDenied when it resolves (through symlinks) outside the root;
// NotFound when missing. Messages quote at most 200 bytes of the path and
// never the root.
Result<std::filesystem::path> ResolveDataPath(const std::filesystem::path& data_root,
                                              std::string_view relative);

// A LoadVolume source under the data root: a path (ResolveDataPath), or a
// DICOM folder with a query, "FOLDER?series=UID&spacing=MM", whose folder
// part is resolved and whose query is kept. Returns the canonical path, with
// "?QUERY" appended when there was one. Errors: those of ResolveDataPath.
Result<std::string> ResolveDataSource(const std::filesystem::path& data_root,
                                      std::string_view source);

// `status` with every mention of `folder` (a data root, an upload's temporary
// folder) taken out of its message: "FOLDER/a/b.nii: ..." reads "a/b.nii: ...",
// and "FOLDER" alone reads `shown_as`. Clients never learn the server's paths.
Status HideFolder(const Status& status, const std::filesystem::path& folder,
                  std::string_view shown_as);

}  // namespace vpm::service

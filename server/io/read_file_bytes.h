// Whole-file reads with the caps applied before allocating, and the rule for
// detached data files named inside headers (.nhdr, .mhd).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// The bytes of the file at `path`, opened by OpenSourceFile (a regular file,
// inside limits.read_root when set; its errors). ResourceExhausted when it is
// larger than limits.max_bytes. Messages start with the path.
Result<std::vector<uint8_t>> ReadFileBytes(const std::filesystem::path& path,
                                           const VolumeLimits& limits);

// Fills `out` with the bytes at [offset, offset + out.size()) of the file at
// `path`, in 16 MiB chunks (limits.read_progress moves, as ReadFileBytes'):
// a reader that knows where the voxels lie reads them straight into the
// volume's storage. OpenSourceFile's errors; InvalidArgument
// when the file ends first.
Status ReadFileRangeInto(const std::filesystem::path& path, int64_t offset,
                         std::span<uint8_t> out, const VolumeLimits& limits);

// Up to the first `count` bytes of the file at `path` (fewer when it is
// shorter): a cheap look at a magic number. OpenSourceFile's errors.
Result<std::vector<uint8_t>> ReadFilePrefix(const std::filesystem::path& path, int64_t count,
                                            const VolumeLimits& limits);

// Loads the data file that a header names (NRRD "data file", MetaImage
// "ElementDataFile"); readers of in-memory headers may pass none.
using DataFileLoader = std::function<Result<std::vector<uint8_t>>(std::string_view name)>;

// A loader that reads `name` next to `header_path`. Only plain relative names
// that stay inside the header's folder are allowed (no absolute paths, no
// ".."): a header handed to a server must not be able to make it read an
// arbitrary file. The file is opened under limits.read_root, so a data file
// that is a symlink leading out of the root is refused too.
DataFileLoader SiblingFileLoader(const std::filesystem::path& header_path,
                                 const VolumeLimits& limits);

}  // namespace vpm

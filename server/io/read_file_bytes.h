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

// The bytes of the file at `path`. NotFound when it does not exist,
// InvalidArgument when it is not a regular file, ResourceExhausted when it is
// larger than limits.max_bytes. Messages start with the path.
Result<std::vector<uint8_t>> ReadFileBytes(const std::filesystem::path& path,
                                           const VolumeLimits& limits);

// Fills `out` with the bytes at [offset, offset + out.size()) of the file at
// `path`, in 16 MiB chunks (limits.read_progress moves, as ReadFileBytes'):
// a reader that knows where the voxels lie reads them straight into the
// volume's storage. NotFound when it cannot be opened, InvalidArgument when
// the file ends first.
Status ReadFileRangeInto(const std::filesystem::path& path, int64_t offset,
                         std::span<uint8_t> out, const VolumeLimits& limits);

// Up to the first `count` bytes of the file at `path` (fewer when it is
// shorter): a cheap look at a magic number. NotFound when it cannot be opened.
Result<std::vector<uint8_t>> ReadFilePrefix(const std::filesystem::path& path, int64_t count);

// Loads the data file that a header names (NRRD "data file", MetaImage
// "ElementDataFile"); readers of in-memory headers may pass none.
using DataFileLoader = std::function<Result<std::vector<uint8_t>>(std::string_view name)>;

// A loader that reads `name` next to `header_path`. Only plain relative names
// that stay inside the header's folder are allowed (no absolute paths, no
// ".."): a header handed to a server must not be able to make it read an
// arbitrary file.
DataFileLoader SiblingFileLoader(const std::filesystem::path& header_path,
                                 const VolumeLimits& limits);

}  // namespace vpm

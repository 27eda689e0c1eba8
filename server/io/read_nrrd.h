// NRRD volumes: .nrrd (header and data in one file) and .nhdr (a header
// naming a detached data file).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "server/common/status.h"
#include "server/io/read_file_bytes.h"
#include "server/volume/volume.h"

namespace vpm {

// Reads a .nrrd or .nhdr file; a detached data file is looked up next to the
// header (read_file_bytes.h says which names are allowed).
// Supported: dimension 2 or 3 (2D becomes nz = 1); types (u)int8/16/32/64,
// float, double; encodings raw, gzip, ascii; endian; line skip, byte skip
// (-1 for raw); "space" left-posterior-superior, right-anterior-superior,
// left-anterior-superior (converted to LPS) or absent (taken as LPS);
// "space directions" (spacing = their lengths, direction = their unit
// vectors, which must be orthonormal), "space origin", or "spacings" alone.
// Errors name the file: NotFound, InvalidArgument (malformed, truncated,
// gzip past the declared size, non-orthonormal directions), ResourceExhausted
// (over `limits`, before allocating), Unimplemented (4D or vector data,
// block type, bzip2/hex encodings, other spaces, multi-file data).
Result<Volume> ReadNrrd(const std::filesystem::path& path, const VolumeLimits& limits);

// The same on the bytes of a header (+ attached data). `loader` resolves a
// detached data file; without one, detached data is an error.
Result<Volume> ReadNrrdFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                  const VolumeLimits& limits, const DataFileLoader& loader = {});

}  // namespace vpm

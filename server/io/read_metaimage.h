// MetaImage volumes (ITK): .mha (header and data in one file) and .mhd (a
// header naming a detached data file).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "server/common/status.h"
#include "server/io/read_file_bytes.h"
#include "server/volume/volume.h"

namespace vpm {

// Reads a .mha or .mhd file; a detached ElementDataFile is looked up next to
// the header (read_file_bytes.h says which names are allowed).
// Supported: NDims 2 or 3 (2D becomes nz = 1); ElementType MET_UCHAR, CHAR,
// USHORT, SHORT, UINT, INT, (U)LONG, (U)LONG_LONG, FLOAT, DOUBLE; byte order;
// CompressedData (zlib, bounded by the declared size); HeaderSize;
// ElementSpacing, Offset, TransformMatrix (its values list the direction of
// axis 0, then of axis 1, ..., as ITK reads them; must be orthonormal).
// AnatomicalOrientation is ignored: coordinates are LPS, as ITK assumes.
// Errors name the file: NotFound, InvalidArgument (malformed, truncated,
// compressed data past the declared size), ResourceExhausted (over
// `limits`, before allocating), Unimplemented (ASCII data, channels, LIST).
Result<Volume> ReadMetaImage(const std::filesystem::path& path, const VolumeLimits& limits);

// The same on the bytes of a header (+ LOCAL data). `loader` resolves a
// detached data file; without one, detached data is an error.
Result<Volume> ReadMetaImageFromMemory(std::span<const uint8_t> bytes, std::string_view name,
                                       const VolumeLimits& limits,
                                       const DataFileLoader& loader = {});

}  // namespace vpm

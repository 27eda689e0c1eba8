// The NRRD header (teem's format: http://teem.sourceforge.net/nrrd/format.html),
// parsed from text.
//
// Why not teem's own nrrdLoad (Debian's libteem)? It trusts the header: it
// allocates sizes * type before reading, follows "data file" to any path,
// and reports errors through a global biff stack. A service reading files
// from users needs every field checked and the caps applied first, so the
// subset we need is parsed here.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/io/byte_order.h"
#include "server/io/voxel_type.h"

namespace vpm {

enum class NrrdEncoding { kRaw, kGzip, kAscii };

struct NrrdHeader {
  int dimension = 0;
  std::vector<int64_t> sizes;  // one per axis, fastest first
  VoxelType type = VoxelType::kUint8;
  Endian endian = Endian::kLittle;
  bool endian_given = false;
  NrrdEncoding encoding = NrrdEncoding::kRaw;
  // "space": the world frame; empty when absent. Converted by the reader.
  std::string space;
  int space_dimension = 0;  // 0 when absent
  // "space directions": one entry per axis, nullopt for "none".
  std::vector<std::optional<glm::dvec3>> space_directions;
  std::optional<glm::dvec3> space_origin;
  std::vector<double> spacings;    // empty when absent
  std::vector<std::string> kinds;  // empty when absent
  std::string data_file;           // empty: data attached
  int64_t line_skip = 0;
  int64_t byte_skip = 0;    // -1: data ends the file (raw only)
  int64_t data_offset = 0;  // attached: first byte after the header
};

// Parses the header at the start of `bytes` (a .nrrd or .nhdr file). An
// attached header ends at its first blank line; a detached one (with a
// "data file") may also end at the end of the bytes. Checks the magic, the
// field syntax and the values' ranges; geometry is checked by the reader.
// InvalidArgument for malformed headers, Unimplemented for features we do not
// read (block type, bzip2 or hex encoding, multi-file data).
Result<NrrdHeader> ParseNrrdHeader(std::span<const uint8_t> bytes);

}  // namespace vpm

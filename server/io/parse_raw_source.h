// The "raw:" source syntax of ReadVolume.
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"
#include "server/io/read_raw.h"

namespace vpm {

struct RawSource {
  std::string path;
  RawOptions options;
};

// Parses "raw:PATH?dims=X,Y,Z&type=T&spacing=A,B,C[&endian=little|big][&offset=N]".
// T: uint8, int8, uint16, int16, uint32, int32, uint64, int64, float32 (or
// float), float64 (or double). The query starts at the last '?'. dims, type
// and spacing are required; endian defaults to little, offset to 0. Unknown
// or repeated keys are errors. InvalidArgument with what is wrong.
Result<RawSource> ParseRawSource(std::string_view source);

}  // namespace vpm

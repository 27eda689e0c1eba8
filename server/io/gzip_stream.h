// Bounded inflation of gzip / zlib streams, and gzip compression (writer).
//
// Compressed volumes are the classic zip bomb: a few kilobytes that inflate
// to gigabytes. Every inflation here is bounded by the size the file's header
// declares (or by a prefix length), and the output buffer grows with the
// data actually produced, so a tiny file claiming a huge volume cannot make
// us allocate the claim before the data is there.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// True when `bytes` starts with the gzip magic (1f 8b).
bool LooksLikeGzip(std::span<const uint8_t> bytes);

// Inflates `compressed` (gzip, possibly several concatenated members, or a
// zlib stream; auto-detected) that must hold exactly `declared_bytes` bytes.
// Errors (messages without a file name; callers add it):
//  - ResourceExhausted when declared_bytes > limits.max_bytes;
//  - InvalidArgument "gzip inflates past the declared size of N bytes"
//    ("zlib data inflates ..." for a zlib stream);
//  - InvalidArgument "... ends after N of the declared M bytes (truncated)";
//  - InvalidArgument for corrupt data.
Result<std::vector<uint8_t>> InflateExactly(std::span<const uint8_t> compressed,
                                            int64_t declared_bytes, const VolumeLimits& limits);

// Inflates at most `prefix_bytes` from the start of `compressed` (fewer when
// the stream is shorter); used to read a header before the size is known.
Result<std::vector<uint8_t>> InflatePrefix(std::span<const uint8_t> compressed,
                                           int64_t prefix_bytes);

// Compresses `data` into a single gzip member (level 6).
Result<std::vector<uint8_t>> GzipCompress(std::span<const uint8_t> data);

}  // namespace vpm

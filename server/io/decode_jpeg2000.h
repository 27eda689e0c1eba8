// One JPEG 2000 codestream (a DICOM frame in transfer syntax
// 1.2.840.10008.1.2.4.90 or .91) decoded with OpenJPEG: DCMTK's open
// decoders do not read JPEG 2000.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/common/status.h"

namespace vpm {

// Decodes `codestream` (a raw J2K codestream, or a JP2 file) that must hold
// one greyscale component of exactly `columns` x `rows` samples; checked from
// the header before any sample is decoded, so a hostile stream cannot make
// it allocate more. Output: columns * rows samples, i fastest, signed when
// the stream says so (as stored: no rescale). InvalidArgument for a stream
// OpenJPEG cannot read or whose size or components disagree.
Result<std::vector<int32_t>> DecodeJpeg2000(std::span<const uint8_t> codestream, int64_t columns,
                                            int64_t rows);

}  // namespace vpm

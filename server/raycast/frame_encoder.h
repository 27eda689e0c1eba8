// Frame encoding for the wire and for files: JPEG through libjpeg-turbo's
// TurboJPEG API (4:2:0, the streaming format) and PNG through libpng's
// simplified API (lossless, for stills and golden images), plus decoders
// for tests. Input and decoded output are RGBA8, row 0 at the top; the
// encoders drop alpha (frames are opaque), the decoders return alpha 255.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/common/status.h"

namespace vpm {

struct DecodedImage {
  std::vector<uint8_t> rgba;  // width * height * 4
  int width = 0;
  int height = 0;
};

// quality in [1, 100]. Errors: InvalidArgument for a bad size or quality
// (rgba.size() must be width * height * 4, sides in 1..65535), Internal
// when the library fails.
Result<std::vector<uint8_t>> EncodeJpeg(std::span<const uint8_t> rgba, int width, int height,
                                        int quality);
Result<std::vector<uint8_t>> EncodePng(std::span<const uint8_t> rgba, int width, int height);

// Errors: InvalidArgument for bytes that are not a decodable image.
Result<DecodedImage> DecodeJpeg(std::span<const uint8_t> bytes);
Result<DecodedImage> DecodePng(std::span<const uint8_t> bytes);

}  // namespace vpm

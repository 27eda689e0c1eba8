// The thumbnail of a series: one of its DICOM instances decoded as the
// readers decode it (ParseDicomFrames: uncompressed, RLE, JPEG, JPEG-LS,
// JPEG 2000), windowed, scaled down and encoded as a grey PNG.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm::pacs {

inline constexpr int kDefaultThumbnailPx = 128;  // the longer side, pixels
inline constexpr int kMaxThumbnailPx = 256;

struct SeriesThumbnail {
  std::vector<uint8_t> png;  // 8-bit grey as RGB, row 0 at the top
  int width = 0;             // pixels
  int height = 0;            // pixels
};

// bytes     one DICOM Part 10 file (the middle frame of a multi-frame one)
// size_px   the longer side of the thumbnail, 16..kMaxThumbnailPx; an image
//           smaller than that keeps its own size. The sides follow the
//           image's physical aspect (PixelSpacing), not its pixel grid.
// limits    the decoder's limits (max_bytes, cancel)
// Windowed by the file's first WindowCenter / WindowWidth (in rescaled
// values), else from the 1st to the 99th percentile of the pixels;
// MONOCHROME1 is inverted. Errors: InvalidArgument for a size outside the
// range, a file that is not DICOM, or one without an image ("holds no
// image": a structured report, a dose report, a presentation state);
// FailedPrecondition for an image that is no slice (a localizer, a
// secondary capture); the decoder's other errors (Unimplemented for colour
// or an unknown compression).
Result<SeriesThumbnail> RenderSeriesThumbnail(std::span<const uint8_t> bytes, int size_px,
                                              const VolumeLimits& limits);

}  // namespace vpm::pacs

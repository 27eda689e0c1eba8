#include "server/pacs/series_thumbnail.h"

#include <dcmtk/config/osconfig.h>  // first among DCMTK headers
#include <dcmtk/dcmdata/dcistrmb.h>
#include <dcmtk/dcmdata/dctk.h>

#include <algorithm>
#include <cmath>

#include "server/io/read_dicom_slice.h"
#include "server/raycast/frame_encoder.h"

namespace vpm::pacs {
namespace {

struct ThumbnailWindow {
  double low = 0;   // rescaled value shown black
  double high = 1;  // rescaled value shown white
  bool invert = false;
};

// The file's own VOI window and photometric interpretation, from its
// header (the pixel data is not read again).
ThumbnailWindow FileWindow(std::span<const uint8_t> bytes) {
  ThumbnailWindow window{.low = 0, .high = 0};
  DcmInputBufferStream in;
  in.setBuffer(bytes.data(), static_cast<offile_off_t>(bytes.size()));
  in.setEos();
  DcmFileFormat file;
  file.transferInit();
  const OFCondition read = file.read(in, EXS_Unknown, EGL_noChange, 1024);  // skip large values
  file.transferEnd();
  if (read.bad()) return window;
  DcmDataset& ds = *file.getDataset();
  OFString photometric;
  if (ds.findAndGetOFString(DCM_PhotometricInterpretation, photometric).good()) {
    window.invert = photometric == "MONOCHROME1";
  }
  Float64 center = 0, width = 0;
  if (ds.findAndGetFloat64(DCM_WindowCenter, center, 0).good() &&
      ds.findAndGetFloat64(DCM_WindowWidth, width, 0).good() && width >= 1 &&
      std::isfinite(center) && std::isfinite(width)) {
    window.low = center - 0.5 - (width - 1) / 2;  // PS3.3 C.11.2.1.2.1
    window.high = center - 0.5 + (width - 1) / 2;
  }
  return window;
}

// The 1st to the 99th percentile of `values` (a sample of at most 64 Ki).
void PercentileWindow(const std::vector<float>& values, ThumbnailWindow* window) {
  std::vector<float> sample;
  const size_t stride = std::max<size_t>(1, values.size() / 65536);
  for (size_t i = 0; i < values.size(); i += stride) {
    if (std::isfinite(values[i])) sample.push_back(values[i]);
  }
  if (sample.empty()) return;
  const auto at = [&](double q) {
    auto nth = sample.begin() + static_cast<ptrdiff_t>(q * double(sample.size() - 1));
    std::nth_element(sample.begin(), nth, sample.end());
    return static_cast<double>(*nth);
  };
  window->low = at(0.01);
  window->high = at(0.99);
  if (window->high <= window->low) window->high = window->low + 1;
}

// The thumbnail's sides for a slice of `columns` x `rows` pixels of
// `spacing_mm` (between rows, between columns): the physical aspect, the
// longer side `size_px` or the slice's own when smaller.
void ThumbnailSides(const DicomSlice& slice, int size_px, int* width, int* height) {
  const double row_mm = slice.pixel_spacing_mm[0] > 0 ? slice.pixel_spacing_mm[0] : 1.0;
  const double col_mm = slice.pixel_spacing_mm[1] > 0 ? slice.pixel_spacing_mm[1] : 1.0;
  const double width_mm = double(slice.columns) * col_mm;
  const double height_mm = double(slice.rows) * row_mm;
  const double longest_px = double(std::max(slice.columns, slice.rows));
  const double side = std::min<double>(size_px, longest_px);
  const double scale = side / std::max(width_mm, height_mm);
  *width = std::clamp(static_cast<int>(std::lround(width_mm * scale)), 1, size_px);
  *height = std::clamp(static_cast<int>(std::lround(height_mm * scale)), 1, size_px);
}

// Each output pixel the mean of the slice's pixels under it (area
// averaging), windowed into 0..255, as RGBA.
std::vector<uint8_t> ScaleAndWindow(const DicomSlice& slice, const ThumbnailWindow& window,
                                    int width, int height) {
  std::vector<uint8_t> rgba(size_t(width) * size_t(height) * 4, 255);
  const double sx = double(slice.columns) / width, sy = double(slice.rows) / height;
  const double span = window.high - window.low;
  for (int y = 0; y < height; ++y) {
    const int64_t y0 = std::min<int64_t>(slice.rows - 1, int64_t(y * sy));
    const int64_t y1 = std::max<int64_t>(y0 + 1, std::min<int64_t>(slice.rows, int64_t((y + 1) * sy)));
    for (int x = 0; x < width; ++x) {
      const int64_t x0 = std::min<int64_t>(slice.columns - 1, int64_t(x * sx));
      const int64_t x1 =
          std::max<int64_t>(x0 + 1, std::min<int64_t>(slice.columns, int64_t((x + 1) * sx)));
      double sum = 0;
      for (int64_t j = y0; j < y1; ++j) {
        for (int64_t i = x0; i < x1; ++i) sum += slice.values[size_t(j * slice.columns + i)];
      }
      const double mean = sum / double((y1 - y0) * (x1 - x0));
      double level = std::clamp((mean - window.low) / span, 0.0, 1.0);
      if (window.invert) level = 1.0 - level;
      const auto grey = static_cast<uint8_t>(std::lround(level * 255.0));
      uint8_t* px = &rgba[(size_t(y) * size_t(width) + size_t(x)) * 4];
      px[0] = px[1] = px[2] = grey;
    }
  }
  return rgba;
}

}  // namespace

Result<SeriesThumbnail> RenderSeriesThumbnail(std::span<const uint8_t> bytes, int size_px,
                                              const VolumeLimits& limits) {
  if (size_px < 16 || size_px > kMaxThumbnailPx) {
    return absl::InvalidArgumentError(
        StrCat("size_px: ", size_px, " is outside 16..", kMaxThumbnailPx));
  }
  if (!LooksLikeDicom(bytes)) {
    return absl::InvalidArgumentError("the instance is not a DICOM Part 10 file");
  }
  ASSIGN_OR_RETURN(std::vector<DicomSlice> frames, ParseDicomFrames(bytes, limits));
  if (frames.empty() || !frames[0].is_image) {
    return absl::InvalidArgumentError(
        "the series holds no image: a structured report, a dose report or a presentation state "
        "has no thumbnail");
  }
  DicomSlice& slice = frames[frames.size() / 2];
  if (!slice.not_a_slice_reason.empty()) {
    return absl::FailedPreconditionError(
        StrCat("the series' instance is a ", slice.not_a_slice_reason, ": no thumbnail"));
  }
  if (slice.rows <= 0 || slice.columns <= 0 ||
      slice.values.size() != size_t(slice.rows * slice.columns)) {
    return absl::InvalidArgumentError("the instance's pixels do not match its Rows and Columns");
  }
  ThumbnailWindow window = FileWindow(bytes);
  if (window.high <= window.low) {
    const bool invert = window.invert;
    PercentileWindow(slice.values, &window);
    window.invert = invert;
  }
  SeriesThumbnail out;
  ThumbnailSides(slice, size_px, &out.width, &out.height);
  const std::vector<uint8_t> rgba = ScaleAndWindow(slice, window, out.width, out.height);
  ASSIGN_OR_RETURN(out.png, EncodePng(rgba, out.width, out.height));
  return out;
}

}  // namespace vpm::pacs

#include "server/raycast/frame_encoder.h"

#include <png.h>
#include <turbojpeg.h>

#include <memory>

namespace vpm {
namespace {

struct TjDeleter {
  void operator()(void* handle) const { tjDestroy(handle); }
};
using TjHandle = std::unique_ptr<void, TjDeleter>;

constexpr int kMaxDecodeSide = 16384;  // the decoders serve tests and tools

Status CheckInput(std::span<const uint8_t> rgba, int width, int height) {
  if (width < 1 || height < 1 || width > 65535 || height > 65535) {
    return absl::InvalidArgumentError(
        StrCat("image of ", width, "x", height, ": sides must be in 1..65535"));
  }
  if (rgba.size() != size_t(width) * size_t(height) * 4) {
    return absl::InvalidArgumentError(StrCat("image of ", width, "x", height, " needs ",
                                             size_t(width) * height * 4, " RGBA bytes, got ",
                                             rgba.size()));
  }
  return absl::OkStatus();
}

}  // namespace

Result<std::vector<uint8_t>> EncodeJpeg(std::span<const uint8_t> rgba, int width, int height,
                                        int quality) {
  RETURN_IF_ERROR(CheckInput(rgba, width, height));
  if (quality < 1 || quality > 100) {
    return absl::InvalidArgumentError(StrCat("JPEG quality ", quality, ": must be in 1..100"));
  }
  TjHandle handle(tjInitCompress());
  if (!handle) return absl::InternalError("tjInitCompress failed");
  unsigned char* jpeg = nullptr;
  unsigned long size = 0;
  if (tjCompress2(handle.get(), rgba.data(), width, width * 4, height, TJPF_RGBA, &jpeg, &size,
                  TJSAMP_420, quality, 0) != 0) {
    const std::string message = tjGetErrorStr2(handle.get());
    tjFree(jpeg);
    return absl::InternalError(StrCat("JPEG encoding failed: ", message));
  }
  std::vector<uint8_t> out(jpeg, jpeg + size);
  tjFree(jpeg);
  return out;
}

Result<DecodedImage> DecodeJpeg(std::span<const uint8_t> bytes) {
  TjHandle handle(tjInitDecompress());
  if (!handle) return absl::InternalError("tjInitDecompress failed");
  int width = 0, height = 0, subsampling = 0, colorspace = 0;
  if (tjDecompressHeader3(handle.get(), bytes.data(), bytes.size(), &width, &height,
                          &subsampling, &colorspace) != 0) {
    return absl::InvalidArgumentError(
        StrCat("not a JPEG image: ", tjGetErrorStr2(handle.get())));
  }
  if (width > kMaxDecodeSide || height > kMaxDecodeSide) {
    return absl::InvalidArgumentError(StrCat("JPEG of ", width, "x", height, " is over ",
                                             kMaxDecodeSide, " per side"));
  }
  DecodedImage image{std::vector<uint8_t>(size_t(width) * height * 4), width, height};
  if (tjDecompress2(handle.get(), bytes.data(), bytes.size(), image.rgba.data(), width,
                    width * 4, height, TJPF_RGBA, 0) != 0) {
    return absl::InvalidArgumentError(
        StrCat("JPEG decoding failed: ", tjGetErrorStr2(handle.get())));
  }
  return image;
}

Result<std::vector<uint8_t>> EncodePng(std::span<const uint8_t> rgba, int width, int height) {
  RETURN_IF_ERROR(CheckInput(rgba, width, height));
  // Opaque frames: store RGB, a quarter smaller.
  std::vector<uint8_t> rgb(size_t(width) * height * 3);
  for (size_t i = 0, n = size_t(width) * height; i < n; ++i) {
    rgb[3 * i] = rgba[4 * i];
    rgb[3 * i + 1] = rgba[4 * i + 1];
    rgb[3 * i + 2] = rgba[4 * i + 2];
  }
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = png_uint_32(width);
  image.height = png_uint_32(height);
  image.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&image, nullptr, &size, 0, rgb.data(), 0, nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    return absl::InternalError(StrCat("PNG encoding failed: ", message));
  }
  std::vector<uint8_t> out(size);
  if (!png_image_write_to_memory(&image, out.data(), &size, 0, rgb.data(), 0, nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    return absl::InternalError(StrCat("PNG encoding failed: ", message));
  }
  out.resize(size);
  return out;
}

Result<DecodedImage> DecodePng(std::span<const uint8_t> bytes) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) {
    const std::string message = image.message;
    png_image_free(&image);
    return absl::InvalidArgumentError(StrCat("not a PNG image: ", message));
  }
  if (image.width > kMaxDecodeSide || image.height > kMaxDecodeSide) {
    png_image_free(&image);
    return absl::InvalidArgumentError(StrCat("PNG of ", image.width, "x", image.height,
                                             " is over ", kMaxDecodeSide, " per side"));
  }
  image.format = PNG_FORMAT_RGBA;
  DecodedImage out{std::vector<uint8_t>(PNG_IMAGE_SIZE(image)), int(image.width),
                   int(image.height)};
  if (!png_image_finish_read(&image, nullptr, out.rgba.data(), 0, nullptr)) {
    const std::string message = image.message;
    png_image_free(&image);
    return absl::InvalidArgumentError(StrCat("PNG decoding failed: ", message));
  }
  return out;
}

}  // namespace vpm

#include "server/io/decode_jpeg2000.h"

#include <openjpeg.h>

#include <algorithm>
#include <cstring>
#include <memory>

namespace vpm {
namespace {

// OpenJPEG reads through callbacks; this one serves a byte span.
struct MemoryReader {
  std::span<const uint8_t> bytes;
  size_t offset = 0;
};

OPJ_SIZE_T Read(void* buffer, OPJ_SIZE_T count, void* user) {
  auto* r = static_cast<MemoryReader*>(user);
  const size_t n = std::min<size_t>(count, r->bytes.size() - r->offset);
  if (n == 0) return static_cast<OPJ_SIZE_T>(-1);  // end of stream, as OpenJPEG expects
  std::memcpy(buffer, r->bytes.data() + r->offset, n);
  r->offset += n;
  return n;
}

OPJ_OFF_T Skip(OPJ_OFF_T count, void* user) {
  auto* r = static_cast<MemoryReader*>(user);
  const OPJ_OFF_T left = static_cast<OPJ_OFF_T>(r->bytes.size() - r->offset);
  const OPJ_OFF_T n = std::clamp<OPJ_OFF_T>(count, -static_cast<OPJ_OFF_T>(r->offset), left);
  r->offset = static_cast<size_t>(static_cast<OPJ_OFF_T>(r->offset) + n);
  return n;
}

OPJ_BOOL Seek(OPJ_OFF_T position, void* user) {
  auto* r = static_cast<MemoryReader*>(user);
  if (position < 0 || static_cast<size_t>(position) > r->bytes.size()) return OPJ_FALSE;
  r->offset = static_cast<size_t>(position);
  return OPJ_TRUE;
}

void Quiet(const char*, void*) {}  // OpenJPEG's messages: errors come back as values

struct CodecDeleter {
  void operator()(opj_codec_t* c) const { opj_destroy_codec(c); }
};
struct StreamDeleter {
  void operator()(opj_stream_t* s) const { opj_stream_destroy(s); }
};
struct ImageDeleter {
  void operator()(opj_image_t* i) const { opj_image_destroy(i); }
};

}  // namespace

Result<std::vector<int32_t>> DecodeJpeg2000(std::span<const uint8_t> codestream, int64_t columns,
                                            int64_t rows) {
  // A JP2 file starts with its signature box; anything else is taken as J2K.
  static constexpr uint8_t kJp2Signature[] = {0, 0, 0, 12, 'j', 'P', ' ', ' '};
  const bool jp2 = codestream.size() >= sizeof(kJp2Signature) &&
                   std::memcmp(codestream.data(), kJp2Signature, sizeof(kJp2Signature)) == 0;
  std::unique_ptr<opj_codec_t, CodecDeleter> codec(
      opj_create_decompress(jp2 ? OPJ_CODEC_JP2 : OPJ_CODEC_J2K));
  opj_set_info_handler(codec.get(), Quiet, nullptr);
  opj_set_warning_handler(codec.get(), Quiet, nullptr);
  opj_set_error_handler(codec.get(), Quiet, nullptr);
  opj_dparameters_t parameters;
  opj_set_default_decoder_parameters(&parameters);
  if (!opj_setup_decoder(codec.get(), &parameters)) {
    return absl::InvalidArgumentError("JPEG 2000: decoder set-up failed");
  }
  MemoryReader reader{codestream, 0};
  std::unique_ptr<opj_stream_t, StreamDeleter> stream(opj_stream_create(1 << 16, OPJ_TRUE));
  opj_stream_set_user_data(stream.get(), &reader, nullptr);
  opj_stream_set_user_data_length(stream.get(), codestream.size());
  opj_stream_set_read_function(stream.get(), Read);
  opj_stream_set_skip_function(stream.get(), Skip);
  opj_stream_set_seek_function(stream.get(), Seek);
  opj_image_t* raw_image = nullptr;
  if (!opj_read_header(stream.get(), codec.get(), &raw_image) || raw_image == nullptr) {
    return absl::InvalidArgumentError("JPEG 2000: unreadable codestream header");
  }
  std::unique_ptr<opj_image_t, ImageDeleter> image(raw_image);
  const int64_t width = int64_t{image->x1} - image->x0;
  const int64_t height = int64_t{image->y1} - image->y0;
  if (image->numcomps != 1 || width != columns || height != rows) {
    return absl::InvalidArgumentError(
        StrCat("JPEG 2000 codestream holds ", image->numcomps, " components of ", width, "x",
               height, " but the DICOM header says 1 of ", columns, "x", rows));
  }
  if (!opj_decode(codec.get(), stream.get(), image.get()) ||
      !opj_end_decompress(codec.get(), stream.get())) {
    return absl::InvalidArgumentError("JPEG 2000: the codestream does not decode (corrupt?)");
  }
  const opj_image_comp_t& c = image->comps[0];
  if (c.data == nullptr || int64_t{c.w} != columns || int64_t{c.h} != rows) {
    return absl::InvalidArgumentError("JPEG 2000: decoded component has the wrong size");
  }
  return std::vector<int32_t>(c.data, c.data + columns * rows);
}

}  // namespace vpm

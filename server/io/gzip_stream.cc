#include "server/io/gzip_stream.h"

#include <zlib.h>

#include <algorithm>
#include <limits>

namespace vpm {
namespace {

// zlib counts in uInt; feed it at most this much per call.
constexpr int64_t kMaxChunk = int64_t{1} << 30;
// Output grows by doubling from here, never beyond the bound.
constexpr int64_t kInitialOutput = int64_t{1} << 20;
// Bytes inflated between two polls of the load's CancelToken (1-3 ms).
constexpr int64_t kOutputStep = int64_t{1} << 20;
// The most address space reserved for the output at once (virtual: a
// declared size that the stream does not fill costs nothing).
constexpr int64_t kMaxReserve = int64_t{1} << 30;

// Owns a z_stream set up for inflation with gzip/zlib auto-detection.
class Inflater {
 public:
  Inflater() { ok_ = inflateInit2(&stream_, 15 + 32) == Z_OK; }
  ~Inflater() {
    if (ok_) inflateEnd(&stream_);
  }
  Inflater(const Inflater&) = delete;
  Inflater& operator=(const Inflater&) = delete;

  bool ok() const { return ok_; }
  z_stream& stream() { return stream_; }

 private:
  z_stream stream_{};
  bool ok_ = false;
};

struct InflateOutcome {
  std::vector<uint8_t> bytes;
  bool more_output = false;  // the stream holds data past `bound`
};

// The full output buffer (`produced` bytes) grown towards `bound`:
// kOutputStep at a time within the reserved address space, else doubled.
void GrowOutput(std::vector<uint8_t>& bytes, int64_t produced, int64_t bound) {
  const int64_t reserved = static_cast<int64_t>(bytes.capacity());
  bytes.resize(static_cast<size_t>(produced < reserved
                                       ? std::min({bound, reserved, produced + kOutputStep})
                                       : std::min(bound, produced * 2 + 1)));
}

// Inflates up to `bound` bytes. Stops early (more_output) when the stream
// would produce more; errors on corrupt or truncated streams unless
// `stop_quietly` (prefix reads tolerate a truncated stream).
Result<InflateOutcome> InflateBounded(std::span<const uint8_t> in, int64_t bound, bool stop_quietly,
                                      const CancelToken& cancel = {}) {
  Inflater inflater;
  if (!inflater.ok()) return absl::InternalError("zlib inflateInit2 failed");
  z_stream& z = inflater.stream();
  InflateOutcome out;
  // Address space for up to kMaxReserve bytes is reserved at once (pages
  // not yet written cost no memory), so the buffer then grows kOutputStep
  // at a time without copying what it holds: no step between two polls of
  // `cancel` copies tens of MiB.
  out.bytes.reserve(static_cast<size_t>(std::min(bound, kMaxReserve)));
  out.bytes.resize(static_cast<size_t>(std::min(bound, kInitialOutput)));
  int64_t produced = 0;
  int64_t consumed = 0;
  const int64_t in_size = static_cast<int64_t>(in.size());
  for (;;) {
    // Each turn inflates at most kOutputStep bytes (a few ms), then polls.
    RETURN_IF_ERROR(cancel.Check());
    if (stop_quietly && produced == bound) break;
    if (produced == static_cast<int64_t>(out.bytes.size()) && produced < bound) {
      GrowOutput(out.bytes, produced, bound);
    }
    uint8_t probe = 0;  // one byte of room past the bound, to detect overrun
    const bool probing = produced == bound;
    z.next_in = const_cast<Bytef*>(in.data() + consumed);
    z.avail_in = static_cast<uInt>(std::min(in_size - consumed, kMaxChunk));
    z.next_out = probing ? &probe : out.bytes.data() + produced;
    // Room left in the buffer, which grows geometrically up to `bound`.
    const int64_t room = static_cast<int64_t>(out.bytes.size()) - produced;
    z.avail_out = probing ? 1u : static_cast<uInt>(std::min(room, kOutputStep));
    const uInt avail_in_before = z.avail_in;
    const uInt avail_out_before = z.avail_out;
    const int rc = inflate(&z, Z_NO_FLUSH);
    consumed += avail_in_before - z.avail_in;
    const int64_t made = avail_out_before - z.avail_out;
    if (probing && made > 0) {
      out.more_output = true;
      break;
    }
    produced += made;
    if (rc == Z_STREAM_END) {
      // Another gzip member may follow (concatenated .gz); trailing bytes that
      // are not a gzip member are ignored, as gzip(1) does.
      if (LooksLikeGzip(in.subspan(static_cast<size_t>(consumed))) && inflateReset(&z) == Z_OK) {
        continue;
      }
      break;
    }
    const bool progress = made > 0 || z.avail_in != avail_in_before;
    if ((rc == Z_OK || rc == Z_BUF_ERROR) && progress) continue;
    if ((rc == Z_OK || rc == Z_BUF_ERROR) && consumed == in_size) {
      if (stop_quietly) break;
      return absl::InvalidArgumentError(StrCat("compressed stream is truncated (ends after ",
                                                     produced, " inflated bytes)"));
    }
    if (stop_quietly && produced > 0) break;
    return absl::InvalidArgumentError(StrCat(
        "compressed data is corrupt (zlib: ", z.msg != nullptr ? z.msg : "no progress", ")"));
  }
  out.bytes.resize(static_cast<size_t>(produced));
  return out;
}

}  // namespace

bool LooksLikeGzip(std::span<const uint8_t> bytes) {
  return bytes.size() >= 2 && bytes[0] == 0x1f && bytes[1] == 0x8b;
}

Result<std::vector<uint8_t>> InflateExactly(std::span<const uint8_t> compressed,
                                            int64_t declared_bytes, const VolumeLimits& limits) {
  if (declared_bytes < 0) {
    return absl::InvalidArgumentError("declared size of compressed data is negative");
  }
  if (declared_bytes > limits.max_bytes) {
    return absl::ResourceExhaustedError(StrCat("declared data of ", declared_bytes,
                                                     " bytes is over the cap of ", limits.max_bytes,
                                                     " bytes"));
  }
  ASSIGN_OR_RETURN(InflateOutcome out,
                   InflateBounded(compressed, declared_bytes, false, limits.cancel));
  if (out.more_output) {
    return absl::InvalidArgumentError(StrCat(LooksLikeGzip(compressed) ? "gzip" : "zlib data",
                                                   " inflates past the declared size of ",
                                                   declared_bytes, " bytes"));
  }
  if (static_cast<int64_t>(out.bytes.size()) < declared_bytes) {
    return absl::InvalidArgumentError(StrCat("compressed data ends after ", out.bytes.size(),
                                                   " of the declared ", declared_bytes,
                                                   " bytes (truncated)"));
  }
  return std::move(out.bytes);
}

Result<std::vector<uint8_t>> InflatePrefix(std::span<const uint8_t> compressed,
                                           int64_t prefix_bytes) {
  ASSIGN_OR_RETURN(InflateOutcome out,
                   InflateBounded(compressed, std::max<int64_t>(prefix_bytes, 0), true));
  return std::move(out.bytes);
}

Result<std::vector<uint8_t>> GzipCompress(std::span<const uint8_t> data) {
  z_stream z{};
  // 15 + 16: a gzip wrapper rather than zlib's.
  if (deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
    return absl::InternalError("zlib deflateInit2 failed");
  }
  std::vector<uint8_t> out;
  size_t done_in = 0;
  int rc = Z_OK;
  while (rc != Z_STREAM_END) {
    const size_t chunk_in = std::min<size_t>(data.size() - done_in, kMaxChunk);
    z.next_in = const_cast<Bytef*>(data.data() + done_in);
    z.avail_in = static_cast<uInt>(chunk_in);
    const int flush = done_in + chunk_in == data.size() ? Z_FINISH : Z_NO_FLUSH;
    const size_t old_size = out.size();
    out.resize(old_size + (size_t{1} << 16));
    z.next_out = out.data() + old_size;
    z.avail_out = 1u << 16;
    rc = deflate(&z, flush);
    done_in += chunk_in - z.avail_in;
    out.resize(out.size() - z.avail_out);
    if (rc == Z_STREAM_ERROR) {
      deflateEnd(&z);
      return absl::InternalError("zlib deflate failed");
    }
  }
  deflateEnd(&z);
  return out;
}

}  // namespace vpm

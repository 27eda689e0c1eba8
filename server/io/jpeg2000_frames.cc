#include "server/io/jpeg2000_frames.h"

namespace vpm {
namespace {

constexpr uint64_t kItemHeaderBytes = 8;  // item tag (4) + length (4)

bool StartsCodestream(std::span<const uint8_t> f) {
  return f.size() >= 4 && f[0] == 0xff && f[1] == 0x4f && f[2] == 0xff && f[3] == 0x51;
}

bool EndsCodestream(const std::vector<uint8_t>& s) {
  size_t n = s.size();
  if (n >= 1 && s[n - 1] == 0x00) --n;  // fragments are padded to even lengths
  return n >= 2 && s[n - 2] == 0xff && s[n - 1] == 0xd9;
}

void Append(std::vector<uint8_t>& to, std::span<const uint8_t> from) {
  to.insert(to.end(), from.begin(), from.end());
}

Result<std::vector<std::vector<uint8_t>>> ByOffsetTable(
    std::span<const uint8_t> table, const std::vector<std::span<const uint8_t>>& fragments,
    int64_t frames) {
  if (table.size() != static_cast<size_t>(frames) * 4) {
    return absl::InvalidArgumentError(StrCat("JPEG 2000: the Basic Offset Table has ",
                                             table.size() / 4, " entries for ", frames,
                                             " frames"));
  }
  std::vector<uint64_t> starts;  // of each fragment item, from the first one's tag
  uint64_t at = 0;
  for (const auto& f : fragments) {
    starts.push_back(at);
    at += kItemHeaderBytes + f.size();
  }
  std::vector<std::vector<uint8_t>> out(static_cast<size_t>(frames));
  size_t fragment = 0;
  for (int64_t frame = 0; frame < frames; ++frame) {
    const uint8_t* e = table.data() + 4 * frame;
    const uint64_t offset = uint64_t{e[0]} | uint64_t{e[1]} << 8 | uint64_t{e[2]} << 16 |
                            uint64_t{e[3]} << 24;
    if (fragment >= fragments.size() || starts[fragment] != offset) {
      return absl::InvalidArgumentError(
          StrCat("JPEG 2000: Basic Offset Table entry ", frame, " (", offset,
                 " bytes) is not the start of the fragment after frame ", frame - 1));
    }
    const uint64_t next = frame + 1 < frames
                              ? (uint64_t{e[4]} | uint64_t{e[5]} << 8 | uint64_t{e[6]} << 16 |
                                 uint64_t{e[7]} << 24)
                              : at;
    do {
      Append(out[frame], fragments[fragment++]);
    } while (fragment < fragments.size() && starts[fragment] < next);
  }
  if (fragment != fragments.size()) {
    return absl::InvalidArgumentError("JPEG 2000: fragments past the Basic Offset Table's frames");
  }
  return out;
}

}  // namespace

Result<std::vector<std::vector<uint8_t>>> Jpeg2000FrameCodestreams(
    std::span<const uint8_t> offset_table, const std::vector<std::span<const uint8_t>>& fragments,
    int64_t frames) {
  if (frames < 1 || fragments.empty()) {
    return absl::InvalidArgumentError(
        StrCat("JPEG 2000: ", fragments.size(), " fragments for ", frames, " frames"));
  }
  std::vector<std::vector<uint8_t>> out;
  if (frames == 1 || static_cast<int64_t>(fragments.size()) == frames) {
    out.resize(static_cast<size_t>(frames));
    for (size_t n = 0; n < fragments.size(); ++n) Append(out[frames == 1 ? 0 : n], fragments[n]);
    return out;
  }
  if (!offset_table.empty()) return ByOffsetTable(offset_table, fragments, frames);
  for (const auto& f : fragments) {
    if (out.empty() || (StartsCodestream(f) && EndsCodestream(out.back()))) out.emplace_back();
    Append(out.back(), f);
  }
  if (static_cast<int64_t>(out.size()) != frames) {
    return absl::InvalidArgumentError(StrCat("JPEG 2000: ", out.size(), " codestreams (SOC ... EOC) in ",
                                             fragments.size(), " fragments for ", frames,
                                             " frames"));
  }
  return out;
}

}  // namespace vpm

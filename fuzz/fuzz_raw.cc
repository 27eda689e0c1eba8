// libFuzzer target: "raw:" source string (the first line) + data (the rest)
// -> ParseRawSource and ReadRawFromMemory.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz/fuzz_limits.h"
#include "server/io/parse_raw_source.h"
#include "server/io/read_raw.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const size_t newline = text.find('\n');
  const std::string_view spec = text.substr(0, newline);
  const size_t data_start = newline == std::string_view::npos ? size : newline + 1;
  const vpm::Result<vpm::RawSource> source = vpm::ParseRawSource(spec);
  if (!source.ok()) return 0;
  vpm::fuzz::CheckVolume(vpm::ReadRawFromMemory({data + data_start, size - data_start},
                                                source->path, source->options,
                                                vpm::fuzz::FuzzLimits()));
  return 0;
}

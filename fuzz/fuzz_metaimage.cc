// libFuzzer target: MetaImage bytes -> ReadMetaImageFromMemory. A detached
// ElementDataFile resolves to the input itself.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_limits.h"
#include "server/io/read_metaimage.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const vpm::DataFileLoader loader = [&](std::string_view) -> vpm::Result<std::vector<uint8_t>> {
    return std::vector<uint8_t>(data, data + size);
  };
  vpm::fuzz::CheckVolume(
      vpm::ReadMetaImageFromMemory({data, size}, "fuzz.mha", vpm::fuzz::FuzzLimits(), loader));
  return 0;
}

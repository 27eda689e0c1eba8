// libFuzzer target: NRRD bytes -> ReadNrrdFromMemory. A detached "data file"
// resolves to the input itself, so the detached path is fuzzed too.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fuzz/fuzz_limits.h"
#include "server/io/read_nrrd.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const vpm::DataFileLoader loader = [&](std::string_view) -> vpm::Result<std::vector<uint8_t>> {
    return std::vector<uint8_t>(data, data + size);
  };
  vpm::fuzz::CheckVolume(
      vpm::ReadNrrdFromMemory({data, size}, "fuzz.nrrd", vpm::fuzz::FuzzLimits(), loader));
  return 0;
}

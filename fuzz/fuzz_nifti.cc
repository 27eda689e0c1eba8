// libFuzzer target: NIfTI-1/2 bytes (plain or gzip) -> ReadNiftiFromMemory.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_limits.h"
#include "server/io/read_nifti.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  vpm::fuzz::CheckVolume(
      vpm::ReadNiftiFromMemory({data, size}, "fuzz.nii", vpm::fuzz::FuzzLimits()));
  return 0;
}

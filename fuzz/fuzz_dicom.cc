// libFuzzer target: one DICOM file's bytes -> ParseDicomFrames (the per-file
// path of the series reader, DCMTK's parser and decoders included).
#include <cstddef>
#include <cstdint>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/oflog/oflog.h>

#include "fuzz/fuzz_limits.h"
#include "server/io/read_dicom_slice.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // DCMTK logs every parse problem; hostile input makes that a flood.
  OFLog::configure(OFLogger::FATAL_LOG_LEVEL);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const vpm::VolumeLimits limits = vpm::fuzz::FuzzLimits();
  const vpm::Result<std::vector<vpm::DicomSlice>> frames =
      vpm::ParseDicomFrames({data, size}, limits);
  if (!frames.ok()) return 0;
  for (const vpm::DicomSlice& slice : *frames) {
    const bool decoded = slice.is_image && slice.not_a_slice_reason.empty();
    if (decoded && static_cast<int64_t>(slice.values.size()) != slice.rows * slice.columns) {
      __builtin_trap();
    }
  }
  return 0;
}

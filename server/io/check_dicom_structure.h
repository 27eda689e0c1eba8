// A walk over the element structure of a DICOM Part 10 file, before DCMTK
// parses it.
//
// Why: DCMTK's parser allocates each element's declared length (up to 4 GB)
// before it finds out whether the stream holds that many bytes, and it
// recurses once per nested sequence. A few hostile bytes can thus make it
// allocate gigabytes or exhaust the stack (our fuzzer found the first within
// seconds). This walk allocates nothing and accepts only files whose every
// element and item fits in the bytes that follow it, whose VRs are standard,
// whose sequences nest at most kMaxDicomNesting deep and which hold at most
// kMaxDicomElements elements; DCMTK then only ever sees such files.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "server/common/status.h"

namespace vpm {

inline constexpr int kMaxDicomNesting = 16;
inline constexpr int64_t kMaxDicomElements = 200000;

// Checks `bytes` (a whole Part 10 file: preamble, "DICM", file meta group,
// dataset) as above. Returns the dataset's transfer syntax UID, one DCMTK
// knows. Errors: InvalidArgument naming the first element that is wrong
// (truncated, bad VR, bad nesting) or for an unknown transfer syntax;
// Unimplemented for the deflated one, which DCMTK would inflate without a
// bound.
Result<std::string> CheckDicomStructure(std::span<const uint8_t> bytes);

}  // namespace vpm

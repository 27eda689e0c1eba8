// STOW-RS: DICOM files sent to a PACS endpoint (POST {dicomweb}/studies,
// multipart/related; type="application/dicom"), in batches of bounded size.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/common/cancel_token.h"
#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/pacs/pacs_endpoint.h"

namespace vpm::pacs {

struct StowOptions {
  int64_t batch_bytes = int64_t{32} << 20;  // one request's body, about
  int64_t connect_timeout_s = 10;
  int64_t stall_timeout_s = 60;
};

struct StowResult {
  int64_t stored = 0;    // instances the PACS answered as stored
  int64_t requests = 0;  // POSTs made
};

// Sends `files` (whole Part 10 files) to `endpoint`. The PACS's answer (DICOM
// JSON) must list every instance as stored: a FailedSOPSequence entry, HTTP
// 202 or 409, or fewer ReferencedSOPSequence items than sent is
// FailedPrecondition ("the PACS refused N of M instances", with the first
// failure reason it gives); HTTP errors as StatusFromHttp; transfer errors
// as HttpPost's. `progress` goes 0..1 by bytes sent.
Result<StowResult> StoreInstances(const PacsEndpoint& endpoint,
                                  const std::vector<const std::string*>& files,
                                  const StowOptions& options, const ProgressFn& progress,
                                  const CancelToken& cancel);

// The stored and failed counts of a STOW-RS answer body (tests).
struct StowAnswer {
  int64_t referenced = 0;
  int64_t failed = 0;
  std::string first_failure;  // FailureReason (0008,1197) of the first failure, as text
};
Result<StowAnswer> ParseStowAnswer(const std::string& body);

}  // namespace vpm::pacs

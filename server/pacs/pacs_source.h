// The LoadVolume source of a series on a PACS:
// "pacs:NAME/STUDY_UID/SERIES_UID[?stack=N]".
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm::pacs {

struct PacsSource {
  std::string endpoint;
  std::string study_uid;
  std::string series_uid;
  // Which of the series' stacks at the same positions (echoes, phases,
  // b-values), 1-based; 0 for the first (DicomReadOptions::stack).
  int64_t stack = 0;
};

inline constexpr std::string_view kPacsPrefix = "pacs:";

// InvalidArgument naming the form for anything else (a bad endpoint name,
// a UID that is not 1-64 digits and dots, a missing part, a query other
// than stack=N).
Result<PacsSource> ParsePacsSource(std::string_view source);

}  // namespace vpm::pacs

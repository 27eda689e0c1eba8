// The DICOM folder source syntax of ReadVolume: "FOLDER[?series=S][&stack=N][&spacing=MM]".
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "server/common/status.h"

namespace vpm {

struct DicomReadOptions {
  // Which series of the folder: "" for the default (the largest CT or MR
  // image series), a SeriesInstanceUID, or a 1-based index N into the list
  // `vpm volume info FOLDER` prints (ListDicomSeries' order).
  std::string series;
  // Which stack of that series (1-based), where it holds several (planes,
  // echoes, phases, b-values: SplitDicomStacks); 0 for the first.
  int64_t stack = 0;
  // Slice spacing of the output grid, mm; 0 keeps the series' own spacing
  // (resampling only uneven or sheared stacks, to their smallest gap).
  double spacing_mm = 0.0;
};

struct DicomSource {
  std::filesystem::path folder;
  DicomReadOptions options;
};

// Returns nullopt when `source` does not name an existing folder (with or
// without a query after its last '?'). Otherwise the folder and its options;
// InvalidArgument for unknown or repeated keys, an empty series, a stack
// that is not a number 1..kMaxDicomStack, a spacing that is not a finite
// number > 0.
Result<std::optional<DicomSource>> ParseDicomSource(std::string_view source);

// The `stack=N` of a folder's or a PACS series' source: 1..kMaxDicomStack,
// else nullopt.
inline constexpr int64_t kMaxDicomStack = 100000;
std::optional<int64_t> ParseStackNumber(std::string_view text);

}  // namespace vpm

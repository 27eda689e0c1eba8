// The bytes a folder reader reads, as a running total held to the cap, so
// that a folder of many files cannot exhaust memory one file at a time.
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include "server/common/status.h"
#include "server/io/read_file_bytes.h"
#include "server/volume/volume.h"

namespace vpm {

class FolderReadBudget {
 public:
  FolderReadBudget(std::filesystem::path folder, const VolumeLimits& limits)
      : folder_(std::move(folder)), limits_(limits) {}

  // The bytes of `file`, counted against limits.max_bytes: ResourceExhausted
  // naming the folder once the files read so far hold more than the cap.
  Result<std::vector<uint8_t>> Read(const std::filesystem::path& file) {
    VolumeLimits remaining = limits_;
    remaining.max_bytes = limits_.max_bytes - bytes_read_;
    Result<std::vector<uint8_t>> bytes = ReadFileBytes(file, remaining);
    if (bytes.status().code() == absl::StatusCode::kResourceExhausted) {
      return absl::ResourceExhaustedError(StrCat(folder_.string(), ": the DICOM files hold over ",
                                                 limits_.max_bytes, " bytes (the cap)"));
    }
    if (bytes.ok()) bytes_read_ += static_cast<int64_t>(bytes->size());
    return bytes;
  }

 private:
  std::filesystem::path folder_;
  VolumeLimits limits_;
  int64_t bytes_read_ = 0;
};

}  // namespace vpm

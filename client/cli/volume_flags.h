// The flags of every offline command that reads a volume: the byte budget
// (--max-volume-bytes, as vpm-server's) and --progress (a progress bar on
// stderr even when it is not a terminal); ReadVolumeForCli reads with both.
#pragma once

#include <cstdint>
#include <string_view>

#include <CLI/CLI.hpp>

#include "server/common/progress.h"
#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm::cli {

struct VolumeFlags {
  int64_t max_volume_bytes = kDefaultMaxVolumeBytes;
  bool progress = false;
};

// Adds --max-volume-bytes and --progress to `command`.
void AddVolumeFlags(CLI::App* command, VolumeFlags* flags);

VolumeLimits ToVolumeLimits(const VolumeFlags& flags);

// ReadVolume(source) under the flags' budget, reporting into `progress`.
Result<Volume> ReadVolumeForCli(std::string_view source, const VolumeFlags& flags,
                                const ProgressFn& progress = {});

}  // namespace vpm::cli

// Caps and result checks shared by the fuzz targets.
#pragma once

#include <cstdint>
#include <cstdlib>

#include "server/volume/volume.h"

namespace vpm::fuzz {

// Small caps keep every input fast and make "over the cap" paths reachable.
inline VolumeLimits FuzzLimits() {
  VolumeLimits limits;
  limits.max_volume_bytes = int64_t{4} << 20;  // 2^20 float voxels
  limits.max_bytes = int64_t{16} << 20;
  return limits;
}

// A reader that says OK must return a consistent volume: traps otherwise, so
// that the fuzzer reports it like a crash.
inline void CheckVolume(const Result<Volume>& volume) {
  if (!volume.ok()) return;
  const VolumeGeometry& g = volume->geometry();
  if (!ValidateGeometry(g, FuzzLimits(), volume->encoding()).ok()) __builtin_trap();
  const VoxelValues& voxels = volume->voxels();
  if (voxels.size() != g.voxel_count()) __builtin_trap();
  for (int64_t n = 0; n < voxels.size(); ++n) {
    const float v = voxels[n];
    if (!(v >= volume->min_value() && v <= volume->max_value())) __builtin_trap();
  }
}

}  // namespace vpm::fuzz

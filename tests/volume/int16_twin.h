// A volume's values rounded to integers (+ offset), held both ways: as int16
// + offset and as float. Kernels and references must give the same results
// for the two (docs/VOLUMES.md, "How values are held").
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "server/volume/volume.h"

namespace vpm::testing {

struct Int16Twin {
  Volume int16;
  Volume floats;
};

inline Int16Twin MakeInt16Twin(const Volume& source, int32_t offset = 0) {
  std::vector<float> rounded = source.voxels().ToFloats();
  std::vector<int16_t> stored(rounded.size());
  for (size_t n = 0; n < rounded.size(); ++n) {
    rounded[n] = std::round(rounded[n]) + float(offset);
    stored[n] = static_cast<int16_t>(static_cast<int32_t>(rounded[n]) - offset);
  }
  return {*Volume::Create(source.geometry(), *VoxelValues::Int16(std::move(stored), offset)),
          *Volume::Create(source.geometry(), std::move(rounded))};
}

}  // namespace vpm::testing

// |grad I| of docs/ALGORITHM.md section 1: central differences in physical units
// (value/mm), indices clamped at the borders:
//   gx = (I[i+1,j,k] - I[i-1,j,k]) / (2*sx), likewise y, z.
// The CPU reference for the GPU kernel, and the oracle in tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "server/volume/volume.h"

namespace vpm {

// |grad I| at one voxel (value/mm), computed in float like the GPU kernel.
inline float GradientMagnitudeAt(const Volume& v, int64_t i, int64_t j, int64_t k) {
  const glm::dvec3& s = v.spacing_mm();
  const float gx = (v.AtClamped(i + 1, j, k) - v.AtClamped(i - 1, j, k)) / float(2.0 * s.x);
  const float gy = (v.AtClamped(i, j + 1, k) - v.AtClamped(i, j - 1, k)) / float(2.0 * s.y);
  const float gz = (v.AtClamped(i, j, k + 1) - v.AtClamped(i, j, k - 1)) / float(2.0 * s.z);
  return std::sqrt(gx * gx + gy * gy + gz * gz);
}

// |grad I| for every voxel, x fastest (same layout as the volume); computed
// on `threads` CPU threads over z slabs. Output: nx*ny*nz floats, value/mm.
std::vector<float> GradientMagnitude(const Volume& volume, int threads = 2);

}  // namespace vpm

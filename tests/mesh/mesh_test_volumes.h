// Small synthetic volumes for the mesh tests: a "body" ellipsoid of soft
// tissue with a "bone" rod and a "vessel" tube, in air, with anisotropic
// spacing. Deterministic.
#pragma once

#include <cmath>

#include "server/volume/volume.h"

namespace vpm::testing {

inline Volume MakeBodyVolume(std::array<int64_t, 3> dims = {48, 40, 32},
                             glm::dvec3 spacing_mm = {1.0, 1.2, 1.5}) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = spacing_mm;
  std::vector<float> values(g.voxel_count());
  const glm::dvec3 c = g.extent_mm() * 0.5;
  uint64_t state = 12345;
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        const glm::dvec3 p = g.IndexToPhysical(glm::dvec3(i, j, k));
        const glm::dvec3 q = (p - c) / (c * 0.85);
        float v = -1000.0f;
        if (glm::dot(q, q) < 1.0) v = 40.0f;                                  // soft tissue
        if (std::hypot(p.x - c.x * 0.6, p.y - c.y * 1.3) < 4.0) v = 700.0f;   // bone rod along z
        if (std::hypot(p.x - c.x * 1.3, p.z - c.z) < 2.5 && glm::dot(q, q) < 1.0) {
          v = 200.0f;  // vessel along y
        }
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        v += static_cast<float>((state >> 33) % 21) - 10.0f;
        values[i + dims[0] * (j + dims[1] * k)] = v;
      }
  return *Volume::Create(g, std::move(values));
}

}  // namespace vpm::testing

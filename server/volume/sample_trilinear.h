// Trilinear sampling of a volume at a point in physical voxel space.
#pragma once

#include <glm/glm.hpp>

#include "server/volume/volume.h"

namespace vpm {

// The volume trilinearly interpolated at p_mm (3, mm, physical voxel space):
// index = p_mm / spacing, clamped to [0, n-1] per axis, so points outside the
// box take the value of the nearest box point (section 0 clamping). Exact for
// a field linear in each coordinate, e.g. I = a + b.x.
double SampleTrilinear(const Volume& volume, const glm::dvec3& p_mm);

}  // namespace vpm

// The point a pixel shows: what a grab by pixel picks ("the server picks the
// 3D point by casting the same ray"). The ray marches the volume front to
// back at the still frame's step (0.5 x the smallest spacing) with the
// frame's preset:
//  - DVR: the first sample where the composited opacity reaches 0.5, the
//    surface the user sees;
//  - MIP: the sample of the largest value, the structure the pixel shows.
// The volume is sampled at rest (trilinear, physical voxel space): picks are
// made before a grab deforms anything, and a release returns to rest.
#pragma once

#include <optional>
#include <span>

#include <glm/glm.hpp>

#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"
#include "server/volume/volume.h"

namespace vpm {

inline constexpr double kPickOpacity = 0.5;  // composited opacity of a DVR pick

// `eye_mm` and the unit `direction` in physical voxel space (mm). nullopt
// when the ray misses the volume's box or stays below kPickOpacity (DVR) /
// sees only the background value (MIP).
// `clip_planes`: the frame's ClipPlanesInPhysical; the ray only looks at
// what the frame shows, so a pick on a cut lands on the cut face.
std::optional<glm::dvec3> PickAlongRay(const Volume& volume, const RenderPreset& preset,
                                       RenderMode mode, const glm::dvec3& eye_mm,
                                       const glm::dvec3& direction,
                                       std::span<const glm::dvec4> clip_planes = {});

}  // namespace vpm

// The CPU reference of the empty-space skipping's two passes:
// brick_minmax.comp (each brick's value range in the source) and
// brick_occupancy.comp (what each brick of deformed space can show), for
// the ray caster's CPU reference (raycast_cpu.h), tests and benchmarks
// (docs/RENDERING.md, "Empty-space skipping").
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"
#include "server/volume/volume.h"

namespace vpm {

struct HostBackwardMap;  // raycast_cpu.h

// Min and max of `volume` per brick of `brick_voxels` voxels per side (x,
// y, z; BrickGridDims bricks, x fastest), as brick_minmax.comp.
std::vector<glm::vec2> BrickMinMaxCpu(const Volume& volume, glm::ivec3 brick_voxels);

// Occupancy per brick of deformed space, as brick_occupancy.comp: DVR 1/0,
// MIP the reachable max. `minmax`: BrickMinMaxCpu for the same brick size;
// `map` may be null (no deformation).
std::vector<float> BrickOccupancyCpu(std::span<const glm::vec2> minmax,
                                     const VolumeGeometry& geometry, glm::ivec3 brick_voxels,
                                     RenderMode mode, const RenderLut& lut,
                                     const HostBackwardMap* map);

}  // namespace vpm

// The organ grab (docs/FEM.md, "The organ grab"): the handles are the
// deformable vertices whose rest position lies in the tissue connected to
// the grab point (organ_region.h) or within a margin of it, plus the few
// nearest to it, so that the organ moves as a body and its surroundings
// follow.
#pragma once

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/fem/fem_model.h"
#include "server/volume/volume.h"

namespace vpm {

// Grabs with `fem` (FemModel::GrabVertices). point_mm: physical voxel space,
// current (deformed) positions; the region is grown in the rest volume from
// the point less the displacement of the nearest vertex. bound_mm: the
// region's largest distance from the point (0: OrganRegionParams default).
// margin_mm: vertices this close to the region are handles too (the mesh's
// vertices are h apart, so those just outside the organ, and those in its
// hilum, carry its boundary voxels: docs/FEM.md, "The organ grab").
// Errors: those of GrowOrganRegion and FemModel::GrabVertices.
Result<GrabInfo> GrabOrgan(const Volume& volume, FemModel& fem, const glm::dvec3& point_mm,
                           double bound_mm, double margin_mm);

}  // namespace vpm

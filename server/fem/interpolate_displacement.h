// The displacement field anywhere in the volume: the FEM vertex
// displacements interpolated linearly through the REST mesh (for the
// section-6 deformation measures, on the CPU).
#pragma once

#include <limits>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/mesh/tet_locator.h"

namespace vpm {

// Displacement at one rest-space point.
//   rest_mesh        a TetLocator over the REST positions (#V) and the tets
//   displacement_mm  #V by 3, mm
//   point_mm         3, mm, rest (physical voxel) space
// Output: sum_c w_c u(tet vertex c) with the barycentric weights w of the
// point in the rest tet that contains it (TetLocator::Locate), mm; nullopt
// outside the mesh. displacement_mm must have one entry per locator vertex.
std::optional<glm::dvec3> InterpolateDisplacement(const TetLocator& rest_mesh,
                                                  const std::vector<glm::dvec3>& displacement_mm,
                                                  const glm::dvec3& point_mm);

// The same at #P points: #P by 3 displacements, mm, `outside` for points no
// tet contains. InvalidArgument when displacement_mm does not have one entry
// per locator vertex.
Result<std::vector<glm::dvec3>> InterpolateDisplacements(
    const TetLocator& rest_mesh, const std::vector<glm::dvec3>& displacement_mm,
    const std::vector<glm::dvec3>& points_mm,
    const glm::dvec3& outside = glm::dvec3(std::numeric_limits<double>::quiet_NaN()));

}  // namespace vpm

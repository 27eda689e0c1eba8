// The permanent Dirichlet constraints of docs/ALGORITHM.md section 5.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

// Which degrees of freedom are fixed (displacement 0) for the whole session:
//   - every DOF of a skeleton vertex (hard and on the skeleton: only the
//     skeleton is fixed; other hard vertices are stiff and free) and of an
//     anchor (the 8 box corners);
//   - on a box face (coordinate within 1e-6 * extent of 0 or of the extent
//     along an axis), the DOF along that face's normal: vertices slide on
//     faces, on an edge they keep one free direction, on a corner none.
// Inputs:
//   mesh            #V vertices, position_mm (mm), kind, hard
//   box_extent_mm   3, the image box [0, extent] (mm), all > 0 and finite
// Output: 3*#V flags (1 fixed, 0 free), vertex v's axis i at 3v + i.
// Fails (InvalidArgument) on a bad extent or a non-finite position.
Result<std::vector<uint8_t>> FixedDofs(const ProxyMesh& mesh, const glm::dvec3& box_extent_mm);

}  // namespace vpm

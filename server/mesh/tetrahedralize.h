// Delaunay tetrahedralization of the proxy mesh (docs/ALGORITHM.md section 5).
#pragma once

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

// Fills mesh.tets with the 3D Delaunay tetrahedralization of the vertex
// positions improved by flips (ImproveTetsByFlips: no longer Delaunay; the
// same vertices and hull, slivers removed where a flip can), mesh.quality
// with MeasureTetQuality, and mesh.stats.tets and
// mesh.stats.tetrahedralize_ms.
//
// Inputs:
//   mesh.vertices   #V vertices, position_mm in physical voxel space (mm);
//                   the 8 corners of the box must be among them
//   box_extent_mm   3, the image box is [0, box_extent_mm] (mm), all > 0
// Outputs:
//   mesh.tets       #T by 4 indices into mesh.vertices, each with positive
//                   signed volume; canonical: each quadruple starts with its
//                   smallest index followed by the smaller of the rest that
//                   an even permutation can bring there, and the list is
//                   sorted lexicographically. The result depends only on the
//                   positions (CGAL's symbolic perturbation makes the
//                   triangulation of cospherical lattice points unique), not
//                   on the insertion order.
//   mesh.quality    min / mean dihedral angle and radius ratio;
//                   removed_zero_volume counts exactly coplanar cells dropped
//
// Fails (InvalidArgument) on fewer than 4 vertices, non-finite positions,
// duplicate positions (listed), all vertices coplanar, vertices outside the
// box, or a triangulation whose volume differs from the box volume by more
// than 1e-9 relative (the hull is not the box: corners missing).
// `cancel` is polled between batches of kInsertBatch insertions and
// before the flips; a cancelled call leaves `mesh` unchanged and returns
// its status.
Status Tetrahedralize(ProxyMesh& mesh, const glm::dvec3& box_extent_mm,
                      const CancelToken& cancel = {});

}  // namespace vpm

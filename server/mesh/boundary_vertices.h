// Vertices on the faces of the image box, added so that no tet at the box is
// a sliver (docs/MESH.md, "Tet quality").
//
// Steps 1-4 keep only the 8 corners on the box, so each face is two
// triangles as large as the face, and the tets between them and the nearest
// kept vertices (h/2 deep where tissue reaches the face) are flat whatever
// the triangulation: 0.2 degrees on the phantom. A quadtree on each face
// puts vertices where they are needed: a cell is split while it is wider
// than depth_ratio times the distance from its centre to the nearest
// vertex, so the face is fine where tissue touches it and coarse where only
// air lies beyond.
#pragma once

#include <vector>

#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

struct BoundaryParams {
  // A face cell wider than this many times the distance from its centre to
  // the nearest vertex is split (dimensionless). 2.5 added 276 vertices to
  // the 250-vertex phantom mesh for a smallest angle of 3.7 degrees, 4 added
  // 103 and 6 added 50, both for 2.7 (docs/MESH.md).
  double depth_ratio = 6.0;
  // Cells are never split below this width, mm (> 0).
  double min_cell_mm = 1.0;
};

// The boundary vertices for `vertices` (#V, mm, physical voxel space; the
// 8 corners among them): kind kBoundary, lattice_id -1, cost 0, voxel the
// nearest voxel, not hard (step 3 classifies them with the rest). Each lies
// on a face of the box [0, geometry.extent_mm()] exactly, none at a corner
// or at the position of another.
std::vector<MeshVertex> BoundaryVertices(const std::vector<MeshVertex>& vertices,
                                         const VolumeGeometry& geometry,
                                         const BoundaryParams& params);

}  // namespace vpm

// Vertices on the faces of the image box, added so that no tet at the box is
// a sliver (docs/MESH.md, "Tet quality").
//
// Steps 1-4 keep only the 8 corners on the box, so each face is two
// triangles as large as the face, and the tets between them and the nearest
// kept vertices (h/2 deep where tissue reaches the face) are flat whatever
// the triangulation: 0.2 degrees on the phantom. A quadtree on each face
// puts vertices where they are needed: a cell is split while it is wider
// than depth_ratio times the depth of the nearest vertex above it (within
// one cell width around it), so the face is fine where tissue touches it and
// coarse where only air lies beyond.
#pragma once

#include <vector>

#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

struct BoundaryParams {
  // A face cell wider than this many times the depth of the vertices above
  // it is split (dimensionless).
  double depth_ratio = 2.5;
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

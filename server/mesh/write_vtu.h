// The proxy mesh as a VTK XML unstructured grid (.vtu), for ParaView and
// 3D Slicer.
#pragma once

#include <string>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"

namespace vpm {

// Writes `mesh` to `path` as ASCII VTK XML UnstructuredGrid (version 0.1):
//   FieldData   SPACE       String "LPS": how 3D Slicer (4.11 and later)
//               and vtkMRMLModelStorageNode learn the points' frame
//   Points      #V by 3 Float64, mm, as given: `vpm mesh` gives world LPS
//               (MeshToWorld, server/mesh/mesh_frame.h)
//   Cells       #T VTK_TETRA (type 10), connectivity Int64, offsets Int64
//   PointData   hard        UInt8  1 = non-deformable (step 3)
//               cost        Float64 MeshVertex::cost
//               kind        Int32  0 = lattice, 1 = anchor, 2 = refined,
//                           3 = boundary, 4 = steiner (the order of VertexKind)
//               lattice_id  Int64  -1 for anchors and refined vertices
// Doubles carry 17 significant digits. Fails on I/O errors, naming the file.
Status WriteVtu(const ProxyMesh& mesh, const std::string& path);

}  // namespace vpm

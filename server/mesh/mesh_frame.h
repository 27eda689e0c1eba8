// The proxy mesh between frames: the compute core builds and deforms it in
// physical voxel space (index * spacing, mm); files and clients get it in the
// world (patient) frame, LPS mm (docs/ALGORITHM.md section 0).
#pragma once

#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

// Positions mapped p -> origin + direction * p (MeshToWorld) or back
// (MeshFromWorld). Where the direction is a reflection (det < 0, which some
// scanners' files carry) the map turns every tet inside out, so two corners
// of each tet swap: every tet keeps a positive signed volume in its frame.
ProxyMesh MeshToWorld(const ProxyMesh& mesh, const VolumeGeometry& geometry);
ProxyMesh MeshFromWorld(const ProxyMesh& mesh, const VolumeGeometry& geometry);

}  // namespace vpm

// The mesh's piecewise-linear version of a volume, for tests and pictures.
#pragma once

#include <limits>
#include <vector>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

// The volume as the mesh sees it: vertex values are the volume trilinearly
// sampled at the vertex positions (SampleTrilinear), linear inside each tet,
// evaluated at every voxel centre (index * spacing, mm).
//
// Inputs:
//   volume         nx by ny by nz values
//   mesh           vertices (mm) and tets
//   outside_value  for voxel centres no tet contains
// Output: nx*ny*nz floats, x fastest (the volume's layout).
Result<std::vector<float>> InterpolateOnMesh(
    const Volume& volume, const ProxyMesh& mesh,
    float outside_value = std::numeric_limits<float>::quiet_NaN(), int threads = 2);

}  // namespace vpm

// Scan conversion of a tet mesh onto the voxel centres of a volume grid,
// carrying the mesh's piecewise-linear interpolant of per-vertex values.
// The shared core of InterpolateOnMesh and MeasureReconstructionError.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Voxels (i_begin .. i_end-1, j, k) whose centres lie in tet `tet`, where the
// mesh interpolant is value_begin + (i - i_begin) * value_step.
struct VoxelRun {
  int64_t i_begin = 0;
  int64_t i_end = 0;
  int64_t j = 0;
  int64_t k = 0;
  int32_t tet = -1;
  double value_begin = 0.0;
  double value_step = 0.0;  // change per voxel along i
};

struct RasterizeTetsOptions {
  int threads = 2;    // z slabs rasterized concurrently
  double eps = 1e-9;  // barycentric slack: a centre is inside when all weights >= -eps
};

// Visits every voxel centre (index * spacing, mm) covered by the mesh exactly
// once, as runs along i. A centre on a shared face, edge or vertex goes to
// the smallest tet index containing it.
//
// Inputs:
//   geometry       the voxel grid (dims, spacing_mm)
//   positions      #V by 3, mm, physical voxel space
//   tets           #T by 4 indices into positions (flat tets are skipped)
//   vertex_values  #V, the values interpolated linearly inside each tet
//   visit          called for each run, concurrently from options.threads
//                  threads; all runs of one slice k come from one thread,
//                  row by row (j ascending, then tet ascending), so
//                  per-slice accumulation is race-free and deterministic
//                  whatever the thread count, and memory is walked in order.
// Output: the number of voxels visited; fails on bad indices or sizes.
Result<int64_t> RasterizeTets(const VolumeGeometry& geometry,
                              const std::vector<glm::dvec3>& positions,
                              const std::vector<std::array<int32_t, 4>>& tets,
                              const std::vector<double>& vertex_values,
                              const RasterizeTetsOptions& options,
                              const std::function<void(const VoxelRun&)>& visit);

}  // namespace vpm

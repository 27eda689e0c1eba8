// Bounded flood fill over a volume's voxels: the face-connected (6
// neighbours) or fully connected (26: faces, edges, corners) set of voxels
// reachable from a seed through voxels a predicate accepts.
// Used for the skeleton (which bone components are large: classify_hardness)
// and the organ grab (the tissue connected to the grab point:
// server/volume/organ_region.h).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "server/volume/volume.h"

namespace vpm {

struct VoxelFlood {
  std::vector<int64_t> voxels;  // linear indices (Volume::LinearIndex), in visiting order
  // False when the fill stopped at max_voxels with voxels still to visit.
  bool complete = true;
};

// Accepts voxel (i, j, k) with linear index `linear`.
using VoxelPredicate = std::function<bool(int64_t i, int64_t j, int64_t k, int64_t linear)>;

// Breadth-first from `seed` (voxel indices; an out-of-range or rejected seed
// gives an empty, complete fill), visiting at most max_voxels (>= 1) voxels.
enum class Connectivity { kFaces6, kFull26 };

VoxelFlood FloodFill(const Volume& volume, const std::array<int64_t, 3>& seed,
                     const VoxelPredicate& accept, int64_t max_voxels,
                     Connectivity connectivity = Connectivity::kFaces6);

}  // namespace vpm

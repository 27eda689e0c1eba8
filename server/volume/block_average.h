// A box of a volume on a coarser grid: each cell the mean of a block of
// factor[0] x factor[1] x factor[2] voxels. The organ region is grown on
// such a grid (organ_region.h), so that its window and its opening act on
// tissue at a few millimetres whatever the scanner's voxel size, and the
// noise of fine voxels averages out.
#pragma once

#include <array>
#include <cstdint>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Which voxels a coarse grid covers: cell c spans the volume's voxels
// lo + factor * c to lo + factor * c + factor - 1 per axis (the last cell of
// an axis may hold fewer, down to one).
struct BlockGrid {
  std::array<int64_t, 3> lo{0, 0, 0};      // first voxel of cell (0, 0, 0)
  std::array<int64_t, 3> factor{1, 1, 1};  // voxels per cell along i, j, k
  std::array<int64_t, 3> dims{0, 0, 0};    // cells along i, j, k

  // The cell holding voxel (i, j, k) of the volume; false when none does.
  bool CellOf(int64_t i, int64_t j, int64_t k, std::array<int64_t, 3>& cell) const;
  // Physical voxel space (mm) of the volume -> of the grid, whose cell c is
  // at c * factor * spacing: the centre of its full block.
  glm::dvec3 VolumeToGrid(const glm::dvec3& p_mm, const glm::dvec3& spacing_mm) const;
};

// Voxels per cell along each axis: floor(cell_mm / spacing), at least 1;
// all 1 when cell_mm <= 0.
std::array<int64_t, 3> BlockFactor(const glm::dvec3& spacing_mm, double cell_mm);

// The grid of blocks of `factor` covering the voxels [lo, lo + size) of
// `volume` (clamped to it), and a volume on it: each cell the mean of the
// voxels of its block, spacing factor x the volume's, direction and origin
// those of physical voxel space (the identity; only its index space is used).
// InvalidArgument for a factor below 1 or an empty box.
Result<Volume> BlockAverage(const Volume& volume, const std::array<int64_t, 3>& lo,
                            const std::array<int64_t, 3>& size,
                            const std::array<int64_t, 3>& factor, BlockGrid& grid);

}  // namespace vpm

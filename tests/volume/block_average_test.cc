// The working grid of the organ region (block_average.h): each cell the
// mean of its block, partial blocks at the box's far edges, cells found
// from voxels and points mapped between the two grids.
#include "server/volume/block_average.h"

#include <gtest/gtest.h>

namespace vpm {
namespace {

TEST(BlockAverage, EachCellIsItsBlocksMeanAndTheLastCellsArePartial) {
  VolumeGeometry g;
  g.dims = {7, 5, 4};
  g.spacing_mm = {0.5, 1.0, 2.0};
  std::vector<float> values(g.voxel_count());
  for (int64_t n = 0; n < g.voxel_count(); ++n) values[n] = float(n);
  const Volume volume = *Volume::Create(g, std::move(values));
  BlockGrid grid;
  auto coarse = BlockAverage(volume, {1, 0, 0}, {6, 5, 4}, {3, 2, 1}, grid);
  ASSERT_TRUE(coarse.ok()) << coarse.status();
  EXPECT_EQ(grid.dims, (std::array<int64_t, 3>{2, 3, 4}));
  EXPECT_EQ(coarse->spacing_mm(), glm::dvec3(1.5, 2.0, 2.0));
  // Cell (1, 2, 3): voxels i 4-6, j 4 (the last, partial), k 3.
  float sum = 0.0f;
  for (int64_t i = 4; i <= 6; ++i) sum += volume.At(i, 4, 3);
  EXPECT_FLOAT_EQ(coarse->At(1, 2, 3), sum / 3.0f);
  std::array<int64_t, 3> cell{};
  ASSERT_TRUE(grid.CellOf(6, 4, 3, cell));
  EXPECT_EQ(cell, (std::array<int64_t, 3>{1, 2, 3}));
  EXPECT_FALSE(grid.CellOf(0, 0, 0, cell));  // left of the box
  // Voxel (2, 0.5, 0)'s centre: cell (0, 0, 0) at the grid's origin.
  const glm::dvec3 p = grid.VolumeToGrid(glm::dvec3(2.0, 0.5, 0.0) * g.spacing_mm, g.spacing_mm);
  EXPECT_NEAR(glm::length(p), 0.0, 1e-12);
}

TEST(BlockAverage, FactorsAreWholeVoxelsPerCellAndBadBoxesAreErrors) {
  EXPECT_EQ(BlockFactor({0.74, 0.74, 0.27}, 3.0), (std::array<int64_t, 3>{4, 4, 11}));
  EXPECT_EQ(BlockFactor({1.0, 2.0, 5.0}, 3.0), (std::array<int64_t, 3>{3, 1, 1}));
  EXPECT_EQ(BlockFactor({0.5, 0.5, 0.5}, 0.0), (std::array<int64_t, 3>{1, 1, 1}));
  VolumeGeometry g;
  g.dims = {4, 4, 4};
  const Volume volume = *Volume::Create(g, std::vector<float>(64, 1.0f));
  BlockGrid grid;
  EXPECT_EQ(BlockAverage(volume, {0, 0, 0}, {4, 4, 4}, {0, 1, 1}, grid).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(BlockAverage(volume, {5, 0, 0}, {4, 4, 4}, {1, 1, 1}, grid).status().code(),
            absl::StatusCode::kInvalidArgument);
  auto clamped = BlockAverage(volume, {-3, -3, -3}, {20, 20, 20}, {2, 2, 2}, grid);
  ASSERT_TRUE(clamped.ok()) << clamped.status();
  EXPECT_EQ(grid.lo, (std::array<int64_t, 3>{0, 0, 0}));
  EXPECT_EQ(clamped->dims(), (std::array<int64_t, 3>{2, 2, 2}));
}

}  // namespace
}  // namespace vpm

#include "server/mesh/lattice.h"

#include <gtest/gtest.h>

#include "server/mesh/lattice_costs.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

VolumeGeometry Geometry(std::array<int64_t, 3> dims, glm::dvec3 spacing) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = spacing;
  return g;
}

TEST(Lattice, PositionsAndIdsFollowTheSpec) {
  auto lattice = Lattice::Create(Geometry({256, 256, 256}, {1.5, 1.5, 0.9}), {20, 20, 20});
  ASSERT_TRUE(lattice.ok());
  const int64_t id = lattice->Id(3, 4, 5);
  EXPECT_EQ(id, 3 + 20 * (4 + 20 * 5));
  const glm::dvec3 p = lattice->Position(id);
  EXPECT_DOUBLE_EQ(p.x, ((3 + 0.5) * 256 / 20 - 0.5) * 1.5);
  EXPECT_DOUBLE_EQ(p.z, ((5 + 0.5) * 256 / 20 - 0.5) * 0.9);
  EXPECT_DOUBLE_EQ(lattice->h_mm(), 256 * 1.5 / 20);
}

TEST(Lattice, VoxelIsNearestRoundHalfUp) {
  // nx/Gx = 12.8: vertex a=2 sits at index 31.5 exactly, which rounds up to 32.
  auto lattice = Lattice::Create(Geometry({256, 256, 256}, {1.3, 1.0, 1.0}), {20, 20, 20});
  ASSERT_TRUE(lattice.ok());
  EXPECT_EQ(lattice->Voxel(lattice->Id(2, 0, 0))[0], 32);
  for (int64_t a = 0; a < 20; ++a) {
    const double index = (a + 0.5) * 256.0 / 20.0 - 0.5;
    EXPECT_EQ(lattice->Voxel(lattice->Id(a, 0, 0))[0], static_cast<int64_t>(std::floor(index + 0.5)))
        << a;
  }
}

TEST(Lattice, CellsPartitionTheVolume) {
  auto lattice = Lattice::Create(Geometry({37, 10, 5}, {1, 1, 1}), {7, 3, 5});
  ASSERT_TRUE(lattice.ok());
  for (int axis = 0; axis < 3; ++axis) {
    int64_t next = 0;
    for (int64_t c = 0; c < lattice->grid()[axis]; ++c) {
      const auto r = lattice->CellRange(axis, c);
      EXPECT_EQ(r[0], next);
      EXPECT_GT(r[1], r[0]);
      next = r[1];
    }
    EXPECT_EQ(next, lattice->geometry().dims[axis]);
  }
}

TEST(Lattice, RejectsGridsFinerThanTheVolume) {
  EXPECT_EQ(Lattice::Create(Geometry({10, 10, 10}, {1, 1, 1}), {11, 5, 5}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(Lattice::Create(Geometry({10, 10, 10}, {1, 1, 1}), {0, 5, 5}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(LatticeCosts, CellFootprintIsMeanTfAndMaxGradient) {
  const Volume v = testing::MakeBodyVolume({12, 10, 8}, {1.0, 2.0, 0.5});
  auto lattice = Lattice::Create(v.geometry(), {3, 2, 2});
  ASSERT_TRUE(lattice.ok());
  const auto tf = TransferFunction::CtSoftTissue();
  const LatticeCosts costs = EvaluateLatticeCostsCpu(v, *lattice, tf, 2);
  const int64_t id = lattice->Id(1, 1, 0);
  double sum = 0, max_g = 0;
  int n = 0;
  for (int64_t k = 0; k < 4; ++k)
    for (int64_t j = 5; j < 10; ++j)
      for (int64_t i = 4; i < 8; ++i, ++n) {
        sum += tf.Evaluate(v.At(i, j, k));
        max_g = std::max(max_g, GradientMagnitudeAtD(v, i, j, k));
      }
  EXPECT_DOUBLE_EQ(costs.ci_cell[id], sum / n);
  EXPECT_DOUBLE_EQ(costs.g_cell[id], max_g);
  const auto vox = lattice->Voxel(id);
  EXPECT_DOUBLE_EQ(costs.ci_point[id], tf.Evaluate(v.At(vox[0], vox[1], vox[2])));
  const auto cg = NormalizeGradientCost(costs.g_cell);
  EXPECT_DOUBLE_EQ(*std::max_element(cg.begin(), cg.end()), 1.0);
  EXPECT_EQ(NormalizeGradientCost({0.0, 0.0}), (std::vector<double>{0.0, 0.0}));
}

}  // namespace
}  // namespace vpm

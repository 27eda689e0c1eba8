// Step 3's skeleton rule (classify_hardness.h rule 4): only bone components
// of at least skeleton_min_volume_mm3 are skeleton (fixed); a small hard
// island (a stone) is hard but not skeleton, and the vertices it makes hard
// by influence are not skeleton either.
#include <algorithm>

#include <gtest/gtest.h>

#include "server/mesh/classify_hardness.h"

namespace vpm {
namespace {

// 40^3 voxels of 1 mm: soft tissue (40), a bone block of 20^3 mm^3 (8,000
// mm^3, value 1000) at [2, 22)^3, a stone of 3^3 mm^3 (value 1000) centred
// at (32, 32, 32), and one voxel of air (-1000 HU) in the corner (39, 0, 0):
// CT in HU (ct_in_hu.h), so that the HU rules apply.
Volume BlockAndStone() {
  VolumeGeometry g;
  g.dims = {40, 40, 40};
  std::vector<float> values(g.voxel_count(), 40.0f);
  for (int64_t k = 0; k < 40; ++k) {
    for (int64_t j = 0; j < 40; ++j) {
      for (int64_t i = 0; i < 40; ++i) {
        const bool block = i >= 2 && i < 22 && j >= 2 && j < 22 && k >= 2 && k < 22;
        const bool stone = std::abs(i - 32) <= 1 && std::abs(j - 32) <= 1 && std::abs(k - 32) <= 1;
        if (block || stone) values[i + 40 * (j + 40 * k)] = 1000.0f;
      }
    }
  }
  values[39] = -1000.0f;
  return *Volume::Create(g, std::move(values));
}

MeshVertex At(int64_t i, int64_t j, int64_t k) {
  MeshVertex v;
  v.position_mm = glm::dvec3(i, j, k);
  v.voxel = {i, j, k};
  return v;
}

TEST(Skeleton, LargeBoneIsSkeletonAStoneIsHardButFree) {
  const Volume volume = BlockAndStone();
  // Block (twice), stone, soft 6.9 mm from the stone, soft far from both.
  std::vector<MeshVertex> vertices = {At(12, 12, 12), At(20, 3, 3), At(32, 32, 32),
                                      At(36, 36, 36), At(30, 5, 35)};
  ClassifyParams params;
  params.influence_threshold = 30.0;  // soft tissue near bone becomes hard (rule 2)
  // R = 10 mm: influence radius 7.5 mm.
  ASSERT_TRUE(ClassifyHardness(volume, 10.0, params, vertices).ok());
  EXPECT_TRUE(vertices[0].hard && vertices[0].skeleton);
  EXPECT_TRUE(vertices[1].hard && vertices[1].skeleton);   // the same block, filled once
  EXPECT_TRUE(vertices[2].hard);
  EXPECT_FALSE(vertices[2].skeleton);                      // the stone: 27 mm^3
  EXPECT_TRUE(vertices[3].hard);                           // influenced by the stone
  EXPECT_FALSE(vertices[3].skeleton);
  EXPECT_FALSE(vertices[4].hard);
  EXPECT_FALSE(vertices[4].skeleton);
}

TEST(Skeleton, ThresholdZeroMakesEveryHardVertexSkeletonAndOverridesAreSkeleton) {
  const Volume volume = BlockAndStone();
  std::vector<MeshVertex> vertices = {At(32, 32, 32), At(30, 5, 35)};
  ClassifyParams params;
  params.skeleton_min_volume_mm3 = 0.0;
  params.overrides.push_back({.shape = HardnessOverride::Shape::kIds, .ids = {1}});
  ASSERT_TRUE(ClassifyHardness(volume, 8.0, params, vertices).ok());
  EXPECT_TRUE(vertices[0].skeleton);
  EXPECT_TRUE(vertices[1].hard && vertices[1].skeleton);
  params.skeleton_min_volume_mm3 = -1.0;
  EXPECT_FALSE(ClassifyHardness(volume, 8.0, params, vertices).ok());
}

// The block is 8,000 mm^3: with a threshold of 10,000 it is an island too.
TEST(Skeleton, TheVolumeThresholdDecides) {
  const Volume volume = BlockAndStone();
  std::vector<MeshVertex> vertices = {At(12, 12, 12)};
  ClassifyParams params;
  params.skeleton_min_volume_mm3 = 10000.0;
  ASSERT_TRUE(ClassifyHardness(volume, 8.0, params, vertices).ok());
  EXPECT_TRUE(vertices[0].hard);
  EXPECT_FALSE(vertices[0].skeleton);
}

// The same block and stone without the air: not CT in HU (an MRI's
// intensities), so no vertex is hard but by an override.
TEST(Skeleton, NoHuRulesOnAVolumeThatIsNotCt) {
  VolumeGeometry g;
  g.dims = {40, 40, 40};
  const Volume ct = BlockAndStone();
  std::vector<float> values(ct.voxels().size());
  for (int64_t n = 0; n < ct.voxels().size(); ++n) values[n] = std::max(ct.voxels()[n], 0.0f);
  const Volume mri = *Volume::Create(g, std::move(values));
  std::vector<MeshVertex> vertices = {At(12, 12, 12), At(32, 32, 32), At(36, 36, 36)};
  ClassifyParams params;
  params.influence_threshold = 30.0;
  ASSERT_TRUE(ClassifyHardness(mri, 10.0, params, vertices).ok());
  for (const MeshVertex& v : vertices) EXPECT_FALSE(v.hard || v.skeleton);
  params.overrides.push_back({.shape = HardnessOverride::Shape::kIds, .ids = {1}});
  ASSERT_TRUE(ClassifyHardness(mri, 10.0, params, vertices).ok());
  EXPECT_TRUE(vertices[1].hard && vertices[1].skeleton);
  EXPECT_FALSE(vertices[0].hard);
}

}  // namespace
}  // namespace vpm

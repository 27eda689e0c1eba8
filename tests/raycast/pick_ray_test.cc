// PickAlongRay: DVR picks the first surface the ray composites to 0.5
// opacity, MIP the brightest sample, a transparent or missing ray nothing.
#include <gtest/gtest.h>

#include "server/raycast/pick_ray.h"

namespace vpm {
namespace {

// 40^3 voxels of 1 mm: air, a bone slab (700 HU) for x in [20, 30] voxels,
// and a 2000 HU spot at (35, 20, 20) behind it.
Volume MakeSlabVolume() {
  VolumeGeometry g;
  g.dims = {40, 40, 40};
  std::vector<float> values(g.voxel_count(), -1000.0f);
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 20; i <= 30; ++i) values[i + 40 * (j + 40 * k)] = 700.0f;
  values[35 + 40 * (20 + 40 * 20)] = 2000.0f;
  return *Volume::Create(g, std::move(values));
}

class PickRayTest : public ::testing::Test {
 protected:
  Volume volume_ = MakeSlabVolume();
  RenderPreset bone_ = *MakeRenderPreset("ct-bone", volume_);
};

TEST_F(PickRayTest, DvrPicksTheFaceTheRayMeetsFirst) {
  // The face is where the trilinear value crosses from air to bone between
  // voxels 19 and 20; the ray needs a sample or two of bone to composite 0.5.
  auto front = PickAlongRay(volume_, bone_, RenderMode::kDvr, {-50, 20, 20}, {1, 0, 0});
  ASSERT_TRUE(front.has_value());
  EXPECT_GE(front->x, 19.0);
  EXPECT_LE(front->x, 21.0);
  EXPECT_NEAR(front->y, 20.0, 1e-9);
  EXPECT_NEAR(front->z, 20.0, 1e-9);
  auto back = PickAlongRay(volume_, bone_, RenderMode::kDvr, {100, 20, 20}, {-1, 0, 0});
  ASSERT_TRUE(back.has_value());
  // From +x the spot at 35 (2000 HU, clamped to the preset's top) comes
  // first: the ray meets it before the slab's far face at 30.
  EXPECT_GE(back->x, 29.0);
  EXPECT_LE(back->x, 36.0);
  auto beside = PickAlongRay(volume_, bone_, RenderMode::kDvr, {100, 10, 10}, {-1, 0, 0});
  ASSERT_TRUE(beside.has_value());
  EXPECT_GE(beside->x, 29.0);
  EXPECT_LE(beside->x, 31.0);
}

TEST_F(PickRayTest, MipPicksTheBrightestSample) {
  auto p = PickAlongRay(volume_, bone_, RenderMode::kMip, {-50, 20, 20}, {1, 0, 0});
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->x, 35.0, 0.5);
}

TEST_F(PickRayTest, TransparentOrMissingRaysPickNothing) {
  // Through air only (x = 5, along y) and past the volume's box.
  EXPECT_FALSE(PickAlongRay(volume_, bone_, RenderMode::kDvr, {5, -50, 20}, {0, 1, 0}));
  EXPECT_FALSE(PickAlongRay(volume_, bone_, RenderMode::kDvr, {-50, 60, 20}, {1, 0, 0}));
  EXPECT_FALSE(PickAlongRay(volume_, bone_, RenderMode::kMip, {-50, 60, 20}, {1, 0, 0}));
  // Pointing away from the volume.
  EXPECT_FALSE(PickAlongRay(volume_, bone_, RenderMode::kDvr, {-50, 20, 20}, {-1, 0, 0}));
}

}  // namespace
}  // namespace vpm

// The pre-integrated tables a renderer keeps (preintegrated_lut_cache.h):
// the same table as a fresh bake, baked once per preset and step however
// often the frames alternate between steps, the least recently used
// dropped beyond the capacity; and a renderer that goes back to a step
// whose table it kept casts the same pixels as before.
#include <gtest/gtest.h>

#include "server/raycast/preintegrated_lut.h"
#include "server/raycast/preintegrated_lut_cache.h"
#include "tests/raycast/raycast_fixture.h"

namespace vpm {
namespace {

using testing::LitPixels;
using testing::RaycastTest;

RenderPreset Preset(const char* name) {
  const Volume volume = testing::MakeSphereRodVolume();
  return *MakeRenderPreset(name, volume);
}

TEST(PreintegratedLutCache, SameTableAsABakeBakedOncePerPresetAndStep) {
  const RenderPreset soft = Preset("ct-soft-tissue");
  const RenderPreset vessels = Preset("ct-vessels");
  PreintegratedLutCache cache;
  EXPECT_EQ(cache.Table(soft, 0.5), BakePreintegratedLut(soft, 0.5));
  // The interactive step, a rung's and the still's, in turn, as a session
  // moves and rests: three bakes.
  for (int i = 0; i < 4; ++i) {
    for (const double step_mm : {0.5, 1.0, 4.0}) cache.Table(soft, step_mm);
  }
  EXPECT_EQ(cache.bakes(), 3u);
  EXPECT_EQ(cache.Table(soft, 1.0), BakePreintegratedLut(soft, 1.0));
  EXPECT_EQ(cache.Table(vessels, 1.0), BakePreintegratedLut(vessels, 1.0));
  EXPECT_EQ(cache.bakes(), 4u);
  // Capacity 3, most recently used: vessels 1.0, soft 1.0, soft 4.0; soft
  // 0.5 was dropped and is baked again.
  cache.Table(soft, 4.0);
  EXPECT_EQ(cache.bakes(), 4u);
  EXPECT_EQ(cache.Table(soft, 0.5), BakePreintegratedLut(soft, 0.5));
  EXPECT_EQ(cache.bakes(), 5u);
}

TEST_F(RaycastTest, PreintegratedTableKept_SamePixelsBackAtAStep) {
  RenderRequest r = Request(RenderMode::kDvr, "ct-soft-tissue");
  ASSERT_TRUE(r.settings.preintegrated);
  r.settings.step_mm = 0.5;
  auto fine = renderer_->Render(r);
  r.settings.step_mm = 2.0;
  auto coarse = renderer_->Render(r);
  r.settings.step_mm = 0.5;
  auto fine_again = renderer_->Render(r);
  // A fresh renderer's frame at the coarse step: the table uploaded at the
  // change of step is that step's, not the one the buffer held.
  auto fresh = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  r.settings.step_mm = 2.0;
  auto coarse_fresh = (*fresh)->Render(r);
  ASSERT_TRUE(fine.ok() && coarse.ok() && fine_again.ok() && coarse_fresh.ok())
      << fine.status() << coarse.status() << fine_again.status() << coarse_fresh.status();
  EXPECT_GT(LitPixels(*fine), 100);
  EXPECT_NE(coarse->rgba, fine->rgba);
  EXPECT_EQ(fine_again->rgba, fine->rgba);
  EXPECT_EQ(coarse->rgba, coarse_fresh->rgba);
}

}  // namespace
}  // namespace vpm

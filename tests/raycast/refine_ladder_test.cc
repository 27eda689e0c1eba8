// The refinement ladder (refine_ladder.h): a rung is kept only where it
// beats the interactive frames it follows (more rays or a finer step, and
// neither worse), and is the still's request at a multiple of its step;
// rungs come only before a still predicted to take a while.
#include <gtest/gtest.h>

#include "server/raycast/refine_ladder.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

RenderRequest Moving(InteractiveQuality quality, const VolumeGeometry& g) {
  RenderRequest r;
  r.camera = Camera::ForVolume(g);
  r.quality = RenderQuality::kInteractive;
  r.interactive = InteractiveCastFor(quality);
  return r;  // 512 x 512
}

TEST(RefineLadder, KeepsTheRungsThatBeatTheInteractiveFrame) {
  const VolumeGeometry g = testing::PhantomGeometry();
  const std::vector<double> candidates = {4.0, 3.0, 2.0, 1.5};
  // Fast: 256^2 rays at the footprint step (about 0.98 mm here): the rungs
  // at 4 and 3 x 0.375 mm step coarser, so only 2 and 1.5 x remain.
  const RenderRequest fast = Moving(InteractiveQuality::kFast, g);
  ASSERT_GT(RequestStepMm(fast, g), 0.75);
  ASSERT_LT(RequestStepMm(fast, g), 1.125);
  EXPECT_EQ(RefineLadder(fast, g, candidates), (std::vector<double>{2.0, 1.5}));
  EXPECT_EQ(RefineLadder(fast, g), (std::vector<double>{2.0}));
  // Balanced: 256^2 rays at 0.75 mm; a 2 x rung has the step and 4 x the rays.
  EXPECT_EQ(RefineLadder(Moving(InteractiveQuality::kBalanced, g), g),
            (std::vector<double>{2.0}));
  // Sharp: full resolution at 1.5 x the still's step; no rung is finer.
  EXPECT_TRUE(RefineLadder(Moving(InteractiveQuality::kSharp, g), g, candidates).empty());
  // A step the user set is the still's too: a coarser rung shows less.
  RenderRequest fixed = fast;
  fixed.settings.step_mm = 0.5;
  EXPECT_TRUE(RefineLadder(fixed, g, candidates).empty());
  // Out of order, repeated or <= 1: skipped.
  EXPECT_EQ(RefineLadder(fast, g, std::vector<double>{1.5, 2.0, 1.5, 1.0, 0.5}),
            (std::vector<double>{1.5}));
}

TEST(RefineLadder, ARungIsTheStillAtAMultipleOfItsStep) {
  const VolumeGeometry g = testing::PhantomGeometry();
  RenderRequest still = Moving(InteractiveQuality::kFast, g);
  still.quality = RenderQuality::kStill;
  const double step_mm = RequestStepMm(still, g);
  RenderRequest rung = still;
  MakeRefineRung(rung, 2.0, g);
  EXPECT_DOUBLE_EQ(RequestStepMm(rung, g), 2.0 * step_mm);
  EXPECT_EQ(rung.quality, RenderQuality::kStill);
  EXPECT_EQ(rung.settings.jitter_seed, still.settings.jitter_seed);
  RenderRequest same = still;
  MakeRefineRung(same, 1.0, g);
  EXPECT_DOUBLE_EQ(RequestStepMm(same, g), step_mm);
}

// Rungs only before a still that takes a while: a rung costs more than half
// the still, so before a quick one it only puts the still off.
TEST(RefineLadder, RungsOnlyBeforeAStillPredictedSlow) {
  EXPECT_TRUE(StillWorthRungs(250.0, 100.0));
  EXPECT_TRUE(StillWorthRungs(100.0, 100.0));
  EXPECT_FALSE(StillWorthRungs(45.0, 100.0));
  EXPECT_FALSE(StillWorthRungs(0.0, 100.0));
  EXPECT_TRUE(StillWorthRungs(-1.0, 100.0));  // no still cast yet
  EXPECT_TRUE(StillWorthRungs(45.0, 0.0));    // 0: always
}

}  // namespace
}  // namespace vpm

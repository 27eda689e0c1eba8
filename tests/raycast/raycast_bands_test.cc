// How a still is cut for the device: bands of tile rows, one submit each
// or grouped by time, and within a dispatch the rows dealt out to a CPU
// device's threads. Neither moves a pixel or a sample.
#include <gtest/gtest.h>

#include "tests/raycast/raycast_fixture.h"

namespace vpm {
namespace {

using testing::LitPixels;
using testing::RaycastTest;

TEST_F(RaycastTest, StillBands_SameFrameAsOneSubmit) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  auto whole = VolumeRenderer::Create(context(), {.still_band_rays = 0});
  // 100 x 70: 7,000 rays in 4 bands of 1,750, over 9 rows of 8 x 8 tiles
  // (the last one 6 pixels high): band 0 takes tile rows 0, 4, 8, the
  // others two each.
  auto banded = VolumeRenderer::Create(context(), {.still_band_rays = 1750, .still_band_ms = 0});
  ASSERT_TRUE(whole.ok() && banded.ok());
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    SCOPED_TRACE(mode == RenderMode::kDvr ? "DVR" : "MIP");
    // Bands of any length fit: the first still's bands 1 to 3 in one
    // submit (however fast band 0 is), the next still whole.
    auto grouped =
        VolumeRenderer::Create(context(), {.still_band_rays = 1750, .still_band_ms = 1e9});
    ASSERT_TRUE(grouped.ok()) << grouped.status();
    RenderRequest r = Request(mode);
    r.width = 100;
    r.height = 70;
    r.backward_map = &*map;
    r.settings.count_samples = true;
    auto one = (*whole)->Render(r);
    auto cut = (*banded)->Render(r);
    auto two = (*grouped)->Render(r);
    auto next = (*grouped)->Render(r);
    ASSERT_TRUE(one.ok() && cut.ok() && two.ok() && next.ok())
        << one.status() << cut.status() << two.status() << next.status();
    EXPECT_EQ(one->bands, 1);
    EXPECT_EQ(one->submits, 1);
    EXPECT_EQ(cut->bands, 4);
    EXPECT_EQ(cut->submits, 4);
    EXPECT_EQ(two->bands, 4);
    EXPECT_EQ(two->submits, 2);
    EXPECT_EQ(next->bands, 1);
    EXPECT_EQ(next->submits, 1);
    EXPECT_GT(LitPixels(*cut), 100);
    EXPECT_EQ(cut->rgba, one->rgba);
    EXPECT_EQ(cut->samples, one->samples);
    EXPECT_EQ(two->rgba, one->rgba);
    EXPECT_EQ(two->samples, one->samples);
    EXPECT_EQ(next->rgba, one->rgba);
    r.quality = RenderQuality::kInteractive;
    auto interactive = (*banded)->Render(r);
    ASSERT_TRUE(interactive.ok()) << interactive.status();
    EXPECT_EQ(interactive->bands, 1);
  }
}

// Bands of a time: where the last still's cost per ray says a band of
// still_band_rays takes longer than still_band_ms (here 1 ns), the next
// still takes a band per tile row, and its pixels do not move.
TEST_F(RaycastTest, StillBands_ByTime_OneATileRowSameFrame) {
  auto timed = VolumeRenderer::Create(context(), {.still_band_rays = 1750, .still_band_ms = 1e-6});
  ASSERT_TRUE(timed.ok()) << timed.status();
  RenderRequest r = Request(RenderMode::kDvr);
  r.width = 100;
  r.height = 70;
  auto by_rays = (*timed)->Render(r);
  auto by_time = (*timed)->Render(r);
  ASSERT_TRUE(by_rays.ok() && by_time.ok()) << by_rays.status() << by_time.status();
  EXPECT_EQ(by_rays->bands, 4);
  EXPECT_EQ(by_time->bands, 9);
  EXPECT_EQ(by_time->submits, 9);
  EXPECT_EQ(by_time->rgba, by_rays->rgba);
}

// The default: a renderer's first 512^2 still in 8 bands, in 2 to 8
// submits (by the device's speed); the next still's cast predicted from
// its cost per ray.
TEST_F(RaycastTest, StillBands_DefaultEightBandsAndThePrediction) {
  auto fresh = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  EXPECT_EQ((*fresh)->PredictStillMs(512 * 512), -1.0);  // no still yet
  auto still = (*fresh)->Render(Request(RenderMode::kMip, "ct-vessels", 512));
  ASSERT_TRUE(still.ok()) << still.status();
  const double predicted = (*fresh)->PredictStillMs(512 * 512);
  EXPECT_GT(predicted, 0.0);
  EXPECT_DOUBLE_EQ((*fresh)->PredictStillMs(256 * 256), predicted / 4.0);
  EXPECT_EQ(still->bands, int(512 * 512 / kStillBandRays));
  EXPECT_GE(still->submits, 2);
  EXPECT_LE(still->submits, still->bands);
}

// The rows of tiles dealt out to a CPU device's threads (raycast_body.glsl,
// band_row) move no pixel: 100 x 70 is 9 tile rows, so 2 threads take rows
// 0, 2, 4, 6 then 1, 3, 5, 7 (row 8 in place), 3 threads all 9 in runs of
// 3, and with 4 bands of 3 or 2 rows each band deals out its own. A row cast
// twice or never shows as a frame unlike the one cast in order.
TEST_F(RaycastTest, DispatchThreads_SamePixelsForAnyThreadCount) {
  HostBackwardMap host;
  auto map = MakeMap(9, 6.0, &host);
  ASSERT_TRUE(map.ok()) << map.status();
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    SCOPED_TRACE(mode == RenderMode::kDvr ? "DVR" : "MIP");
    RenderRequest r = Request(mode);
    r.width = 100;
    r.height = 70;
    r.backward_map = &*map;
    r.settings.count_samples = true;
    auto in_order =
        VolumeRenderer::Create(context(), {.still_band_rays = 0, .dispatch_threads = 1});
    ASSERT_TRUE(in_order.ok()) << in_order.status();
    auto reference = (*in_order)->Render(r);
    ASSERT_TRUE(reference.ok()) << reference.status();
    EXPECT_GT(LitPixels(*reference), 100);
    for (int64_t band_rays : {int64_t(0), int64_t(1750)}) {
      for (uint32_t threads : {2u, 3u, 4u, 32u}) {
        SCOPED_TRACE(::testing::Message()
                     << band_rays << " rays a band, " << threads << " threads");
        auto renderer = VolumeRenderer::Create(
            context(),
            {.still_band_rays = band_rays, .still_band_ms = 0, .dispatch_threads = threads});
        ASSERT_TRUE(renderer.ok()) << renderer.status();
        auto frame = (*renderer)->Render(r);
        ASSERT_TRUE(frame.ok()) << frame.status();
        EXPECT_EQ(frame->bands, band_rays == 0 ? 1 : 4);
        EXPECT_EQ(frame->rgba, reference->rgba);
        EXPECT_EQ(frame->samples, reference->samples);
      }
    }
  }
}

}  // namespace
}  // namespace vpm

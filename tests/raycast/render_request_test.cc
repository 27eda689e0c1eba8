// What PrepareRaycast decides from the volume's geometry and the camera
// rather than from the voxel count: the empty-space bricks (sized in mm) and
// the interactive step (from the pixel footprint). Both are what make a
// full-size CT cost the same per pixel as the 256^3 phantom
// (docs/RENDERING.md, "Empty-space skipping" and "Quality modes").
#include <cmath>

#include <gtest/gtest.h>

#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

using testing::PhantomGeometry;

// The 512 x 512 x 900 CT made from the 256^3 phantom
// (bench/make_ct_nifti.cc): the same field of view, voxels 2 x 2 x 3.5
// times smaller.
VolumeGeometry FullSizeCtGeometry() {
  VolumeGeometry g;
  g.dims = {512, 512, 900};
  g.spacing_mm = {380.0 / 511.0, 380.0 / 511.0, 243.0 / 899.0};
  return g;
}

glm::dvec3 BrickMm(RenderQuality q, const VolumeGeometry& g) {
  return glm::dvec3(BrickVoxels(q, g)) * g.spacing_mm;
}

TEST(RenderRequest, BricksAreSizedInMillimetres) {
  for (RenderQuality q : {RenderQuality::kStill, RenderQuality::kInteractive}) {
    const double target = q == RenderQuality::kStill ? kStillBrickMm : kInteractiveBrickMm;
    for (const VolumeGeometry& g : {PhantomGeometry(), FullSizeCtGeometry()}) {
      const glm::dvec3 mm = BrickMm(q, g);
      for (int a = 0; a < 3; ++a) {
        // Rounding to whole voxels: within half a voxel of the target.
        EXPECT_NEAR(mm[a], target, 0.5 * g.spacing_mm[a] + 1e-9) << "axis " << a;
      }
    }
    // So both volumes have about as many bricks, whatever their slice count.
    const auto bp = BrickGridDims(PhantomGeometry().dims, BrickVoxels(q, PhantomGeometry()));
    const auto bc = BrickGridDims(FullSizeCtGeometry().dims, BrickVoxels(q, FullSizeCtGeometry()));
    const double phantom = double(bp[0]) * bp[1] * bp[2];
    const double ct = double(bc[0]) * bc[1] * bc[2];
    EXPECT_LT(std::abs(ct / phantom - 1.0), 0.25) << "phantom " << phantom << ", CT " << ct;
  }
  // The phantom keeps the in-plane bricks it was tuned with (4 still, 8
  // interactive voxels).
  EXPECT_EQ(BrickVoxels(RenderQuality::kStill, PhantomGeometry()).x, 4);
  EXPECT_EQ(BrickVoxels(RenderQuality::kInteractive, PhantomGeometry()).x, 8);
}

TEST(RenderRequest, BricksStayWithinTheVolume) {
  VolumeGeometry coarse;  // 20 mm voxels: a brick is one voxel
  coarse.dims = {4, 3, 2};
  coarse.spacing_mm = {20.0, 20.0, 20.0};
  EXPECT_EQ(BrickVoxels(RenderQuality::kInteractive, coarse), glm::ivec3(1, 1, 1));
  VolumeGeometry fine;  // 0.01 mm voxels, few of them: one brick per axis
  fine.dims = {6, 300, 2};
  fine.spacing_mm = {0.01, 0.01, 0.01};
  EXPECT_EQ(BrickVoxels(RenderQuality::kStill, fine), glm::ivec3(5, 299, 1));
  const auto nb = BrickGridDims(fine.dims, BrickVoxels(RenderQuality::kStill, fine));
  EXPECT_EQ(nb, (std::array<int, 3>{1, 1, 1}));  // one brick spans each axis
}

RenderRequest Interactive(const VolumeGeometry& g, int side) {
  RenderRequest r;
  r.camera = Camera::ForVolume(g);
  r.quality = RenderQuality::kInteractive;
  r.width = side;
  r.height = side;
  return r;
}

TEST(RenderRequest, InteractiveStepFollowsThePixelNotTheVoxels) {
  const VolumeGeometry phantom = PhantomGeometry(), ct = FullSizeCtGeometry();
  // 256^2 frames (128^2 rays): the same step on both volumes, half the
  // footprint of a ray-cast pixel.
  RenderRequest rp = Interactive(phantom, 256), rc = Interactive(ct, 256);
  const double sp = RequestStepMm(rp, phantom), sc = RequestStepMm(rc, ct);
  EXPECT_NEAR(sp, sc, 1e-9);
  const Camera::Pose& pose = rp.camera.pose();
  const double footprint =
      2.0 * pose.distance_mm * std::tan(0.5 * pose.fov_deg * std::acos(-1.0) / 180.0) / 128.0;
  EXPECT_NEAR(sp, kInteractiveStepPerPixel * footprint, 1e-9);
  EXPECT_GT(sp, ct.spacing_mm.z * 3.0);  // far coarser than the CT's slices
  // Twice the pixels, half the step, down to the smallest spacing.
  rp.width = rp.height = 512;
  EXPECT_NEAR(RequestStepMm(rp, phantom), std::max(0.5 * sp, phantom.spacing_mm.z), 1e-9);
  rc.width = rc.height = 512;
  EXPECT_NEAR(RequestStepMm(rc, ct), 0.5 * sc, 1e-9);
  // Zoomed in, the pixel shrinks below a voxel: the smallest spacing.
  rc.camera.Zoom(20.0);
  EXPECT_DOUBLE_EQ(RequestStepMm(rc, ct), kInteractiveStepFactor * ct.spacing_mm.z);
  // Far away: no coarser than the diagonal / kInteractiveMinSamplesPerRay.
  rc.camera.Zoom(1.0 / 2000.0);
  EXPECT_NEAR(RequestStepMm(rc, ct), glm::length(ct.extent_mm()) / kInteractiveMinSamplesPerRay,
              1e-9);
  // Stills keep the spacing rule, and an explicit step wins.
  rc.quality = RenderQuality::kStill;
  rc.mode = RenderMode::kMip;
  EXPECT_DOUBLE_EQ(RequestStepMm(rc, ct), kStillMipStepFactor * ct.spacing_mm.z);
  rc.quality = RenderQuality::kInteractive;
  rc.settings.step_mm = 0.4;
  EXPECT_DOUBLE_EQ(RequestStepMm(rc, ct), 0.4);
}

// The interactive qualities on a coarse CT (3 mm voxels, as the kidney CT):
// fast keeps the footprint step, floored at one voxel; balanced and sharp
// cap it at 2 and 1.5 x the still's step (0.375 mm there), sharp on a full
// grid of rays. Casts outside their ranges are refused by name.
TEST(RenderRequest, InteractiveQualitiesCapTheStepAndSizeTheRayGrid) {
  VolumeGeometry coarse;
  coarse.dims = {122, 101, 112};
  coarse.spacing_mm = {3.0, 3.0, 3.0};
  RenderRequest r = Interactive(coarse, 512);
  r.preset = *MakeRenderPreset("ct-soft-tissue", testing::MakeSphereRodVolume(16));
  r.interactive = InteractiveCastFor(InteractiveQuality::kFast);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, coarse), 3.0);
  r.interactive = InteractiveCastFor(InteractiveQuality::kBalanced);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, coarse), 2.0 * kStillMaxStepMm);
  r.interactive = InteractiveCastFor(InteractiveQuality::kSharp);
  EXPECT_DOUBLE_EQ(RequestStepMm(r, coarse), 1.5 * kStillMaxStepMm);
  auto sharp = PrepareRaycast(r, coarse, {0, 0, 0});
  ASSERT_TRUE(sharp.ok()) << sharp.status();
  EXPECT_EQ(sharp->render_width, 512);
  // Full resolution skips by still bricks (3 mm voxels: 2 per 6 mm brick).
  EXPECT_EQ(glm::ivec3(sharp->params.brick_voxels), BrickVoxels(RenderQuality::kStill, coarse));
  r.interactive = InteractiveCastFor(InteractiveQuality::kBalanced);
  auto balanced = PrepareRaycast(r, coarse, {0, 0, 0});
  ASSERT_TRUE(balanced.ok()) << balanced.status();
  EXPECT_EQ(balanced->render_width, 256);
  EXPECT_EQ(glm::ivec3(balanced->params.brick_voxels),
            BrickVoxels(RenderQuality::kInteractive, coarse));
  r.interactive.divisor = 1.5;
  auto third = PrepareRaycast(r, coarse, {0, 0, 0});
  ASSERT_TRUE(third.ok()) << third.status();
  EXPECT_EQ(third->render_width, 342);  // ceil(512 / 1.5)
  for (InteractiveCast bad : {InteractiveCast{0.5, 0.0, gpu::kUpscaleBilinear},
                              InteractiveCast{5.0, 0.0, gpu::kUpscaleBilinear},
                              InteractiveCast{2.0, std::nan(""), gpu::kUpscaleBilinear},
                              InteractiveCast{2.0, 0.0, 7}}) {
    r.interactive = bad;
    auto refused = PrepareRaycast(r, coarse, {0, 0, 0});
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  }
}

// A still stepping kCoarseGridStepMm or more skips by the interactive
// bricks (a still brick would hold 4 samples or fewer); finer stills keep
// the still bricks.
TEST(RenderRequest, CoarseStepsSkipByInteractiveBricks) {
  const VolumeGeometry phantom = PhantomGeometry();
  RenderRequest r = Interactive(phantom, 128);
  r.quality = RenderQuality::kStill;
  r.preset = *MakeRenderPreset("ct-soft-tissue", testing::MakeSphereRodVolume(16));
  for (double step : {0.5, 1.0, 1.49, 1.5, 3.0}) {
    r.settings.step_mm = step;
    auto setup = PrepareRaycast(r, phantom, {0, 0, 0});
    ASSERT_TRUE(setup.ok()) << setup.status();
    const RenderQuality grid =
        step >= kCoarseGridStepMm ? RenderQuality::kInteractive : RenderQuality::kStill;
    EXPECT_EQ(glm::ivec3(setup->params.brick_voxels), BrickVoxels(grid, phantom)) << step;
  }
}

}  // namespace
}  // namespace vpm

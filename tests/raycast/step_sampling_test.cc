// Sampling along the rays: jittered ray starts (one seed, one picture; GPU
// and CPU reference the same jitter) and stills that hold against the same
// renderer at an eighth of the step on a real CT (docs/RENDERING.md,
// "Sampling").
//
// Tolerances: GPU against CPU as raycast_test.cc (mean < 1/255, max <
// 8/255); a still against step / 8: PSNR >= 40 dB (issue 29).
#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "server/io/read_volume.h"
#include "server/raycast/clip_region.h"
#include "server/raycast/ray_start_jitter.h"
#include "server/raycast/raycast_cpu.h"
#include "server/raycast/volume_renderer.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

using testing::CompareRgba;
using testing::MaybeDump;

TEST(RayStartJitter, UniformOverTheStepAndUnrelatedBetweenNeighbours) {
  double sum = 0.0;
  int close_neighbours = 0, bins[8] = {};
  const int n = 256;
  for (uint32_t y = 0; y < n; ++y) {
    for (uint32_t x = 0; x < n; ++x) {
      const float j = RayStartJitter(x, y, 0);
      ASSERT_GE(j, 0.0f);
      ASSERT_LT(j, 1.0f);
      sum += j;
      ++bins[int(j * 8)];
      close_neighbours += std::abs(j - RayStartJitter(x + 1, y, 0)) < 0.01f;
    }
  }
  EXPECT_NEAR(sum / (n * n), 0.5, 0.01);
  for (int b : bins) EXPECT_NEAR(b, n * n / 8, n * n / 80);
  // Independent uniforms: |a - b| < 0.01 with probability ~0.02.
  EXPECT_LT(close_neighbours, n * n / 25);
  // The seed changes the pattern.
  int same = 0;
  for (uint32_t x = 0; x < 1000; ++x) same += RayStartJitter(x, 3, 0) == RayStartJitter(x, 3, 1);
  EXPECT_LT(same, 5);
}

class StepSamplingTest : public testing::GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    auto renderer = VolumeRenderer::Create(context(), {});
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    renderer_ = std::move(*renderer);
  }

  void Load(Volume volume) {
    volume_.emplace(std::move(volume));
    auto gpu = GpuVolume::Upload(context(), *volume_);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    gpu_volume_.emplace(std::move(*gpu));
  }

  RenderRequest Request(RenderMode mode, const std::string& preset, int size) {
    RenderRequest r;
    r.camera = Camera::ForVolume(volume_->geometry());
    r.mode = mode;
    r.preset = *MakeRenderPreset(preset, *volume_);
    r.width = size;
    r.height = size;
    r.volume = &*gpu_volume_;
    return r;
  }

  Frame Gpu(const RenderRequest& r) {
    auto frame = renderer_->Render(r);
    EXPECT_TRUE(frame.ok()) << frame.status();
    return frame.ok() ? std::move(*frame) : Frame{};
  }

  std::unique_ptr<VolumeRenderer> renderer_;
  std::optional<Volume> volume_;
  std::optional<GpuVolume> gpu_volume_;
};

TEST_F(StepSamplingTest, Jitter_OneSeedOnePicture) {
  Load(testing::MakeSphereRodVolume());
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    RenderRequest r = Request(mode, "ct-vessels", 96);
    r.camera.Orbit(30.0, 20.0);
    const Frame first = Gpu(r);
    const Frame again = Gpu(r);
    EXPECT_EQ(first.rgba, again.rgba) << "a still with one seed is reproducible";
    r.settings.jitter_seed = 1;
    const Frame other_seed = Gpu(r);
    r.settings.jitter = false;
    const Frame unjittered = Gpu(r);
    EXPECT_NE(first.rgba, other_seed.rgba) << "another seed, other sample depths";
    EXPECT_NE(first.rgba, unjittered.rgba);
    // Noise of a fraction of the step, not another picture.
    EXPECT_GT(CompareRgba(first.rgba, other_seed.rgba).psnr_db, 30.0);
    EXPECT_GT(CompareRgba(first.rgba, unjittered.rgba).psnr_db, 30.0);
  }
}

TEST_F(StepSamplingTest, Jitter_GpuMatchesCpuReference) {
  Load(testing::MakeSphereRodVolume());
  for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
    for (bool cell : {true, false}) {
      if (mode == RenderMode::kMip && !cell) continue;
      RenderRequest r = Request(mode, "ct-soft-tissue", 96);
      r.camera.Orbit(-20.0, 10.0);
      r.settings.jitter_seed = 12345;
      r.settings.still_cell_gradient = cell;
      // A coarse step, so that the jitter moves samples by a lot.
      r.settings.step_mm = 2.5;
      const Frame gpu = Gpu(r);
      auto cpu = RenderReference(r, *volume_, nullptr, 2);
      ASSERT_TRUE(cpu.ok()) << cpu.status();
      const auto e = CompareRgba(gpu.rgba, cpu->rgba);
      const char* what = mode == RenderMode::kMip ? "MIP" : (cell ? "DVR cell" : "DVR taps");
      EXPECT_LT(e.mean_abs, 1.0 / 255) << what;
      EXPECT_LT(e.max_abs, 8.0 / 255) << what;
      r.settings.jitter = false;
      EXPECT_NE(Gpu(r).rgba, gpu.rgba) << what << ": the jitter moved no sample";
    }
  }
}

// Issue 29's measure on the real abdominal CT (3 mm voxels): every CT
// preset's still, and MIP, within 40 dB of the same renderer at step / 8,
// from the default camera and through the view cut (the clients' first
// frame). Unjittered, CT-Soft-Tissue's opaque skin showed rings at 34 dB
// (docs/RENDERING.md, "Sampling").
TEST_F(StepSamplingTest, DISABLED_KidneyCtStills_WithinFortyDbOfAnEighthOfTheStep) {
  auto volume = ReadVolume(
      std::string(VPM_TEST_SOURCE_DIR) + "/tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz", {});
  ASSERT_TRUE(volume.ok()) << volume.status();
  Load(std::move(*volume));
  const VolumeGeometry& g = volume_->geometry();
  for (const char* preset : {"ct-soft-tissue", "ct-bone", "ct-vessels", "CT-AAA", "CT-Bone",
                             "CT-Muscle", "CT-Chest-Contrast-Enhanced", "CT-Soft-Tissue", "mip"}) {
    for (bool cut : {false, true}) {
      const bool mip = std::string(preset) == "mip";
      RenderRequest r = Request(mip ? RenderMode::kMip : RenderMode::kDvr,
                                mip ? "ct-vessels" : preset, 192);
      if (cut) {
        r.clip.planes.push_back(CutPlaneFacing(g.PhysicalToWorld(r.camera.Target()),
                                               g.direction * r.camera.Forward()));
      }
      const Frame still = Gpu(r);
      r.settings.step_mm = still.step_mm / 8.0;
      const Frame fine = Gpu(r);
      const double psnr = CompareRgba(still.rgba, fine.rgba).psnr_db;
      EXPECT_GE(psnr, 40.0) << preset << (cut ? ", cut" : "") << ": step " << still.step_mm
                            << " mm";
      MaybeDump(std::string("kidney_step_") + preset + (cut ? "_cut" : ""), still.rgba,
                still.width, still.height);
    }
  }
}

}  // namespace
}  // namespace vpm

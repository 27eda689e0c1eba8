// Interactive frames per InteractiveQuality (render_request.h): the GPU
// against the CPU reference for each setting (ray grid, step, upscale
// filter), the Catmull-Rom upscale's own properties, and each setting's
// PSNR against the still on the phantom at no less than the floor
// docs/RENDERING.md ("Interactive quality") gives.
//
// Tolerances: GPU against CPU as raycast_test.cc's interactive frames (mean
// < 1/255, max < 8/255); the upscales alone: max 1/255 (float rounding of
// the same sums).
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/gpu/shader_interface.h"
#include "server/io/read_volume.h"
#include "server/phantom/phantom.h"
#include "server/raycast/raycast_cpu.h"
#include "server/raycast/upscale_cpu.h"
#include "server/raycast/volume_renderer.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

using testing::CompareRgba;
using testing::MaybeDump;

constexpr InteractiveQuality kQualities[] = {
    InteractiveQuality::kFast, InteractiveQuality::kBalanced, InteractiveQuality::kSharp};

const char* Name(InteractiveQuality q) {
  return q == InteractiveQuality::kFast       ? "fast"
         : q == InteractiveQuality::kBalanced ? "balanced"
                                              : "sharp";
}

uint32_t Pack(int r, int g, int b, int a) {
  return uint32_t(r) | (uint32_t(g) << 8) | (uint32_t(b) << 16) | (uint32_t(a) << 24);
}

// A constant image stays constant, a ramp along x stays a ramp inside (the
// cubic reproduces linear functions), and the overshoot at a step edge is
// clamped to [0, 255].
// The names every client's --interactive-quality flag takes, and no other.
TEST(InteractiveQualityNames, TheFourNamesAndNoOther) {
  EXPECT_EQ(InteractiveQualityNamed("auto"), InteractiveQuality::kAuto);
  EXPECT_EQ(InteractiveQualityNamed("fast"), InteractiveQuality::kFast);
  EXPECT_EQ(InteractiveQualityNamed("balanced"), InteractiveQuality::kBalanced);
  EXPECT_EQ(InteractiveQualityNamed("sharp"), InteractiveQuality::kSharp);
  for (const char* other : {"", "Fast", "sharp ", "ultra"}) {
    EXPECT_FALSE(InteractiveQualityNamed(other).has_value()) << other;
  }
}

TEST(UpscaleCpu, CatmullRomKeepsConstantsAndRampsAndClampsOvershoot) {
  const int sw = 16, sh = 8, tw = 32, th = 16;
  std::vector<uint32_t> flat(sw * sh, Pack(10, 200, 77, 255));
  for (uint32_t p : UpscaleCpu(flat, sw, sh, tw, th, gpu::kUpscaleCatmullRom)) {
    ASSERT_EQ(p, Pack(10, 200, 77, 255));
  }
  std::vector<uint32_t> ramp(sw * sh), edge(sw * sh);
  for (int y = 0; y < sh; ++y)
    for (int x = 0; x < sw; ++x) {
      ramp[y * sw + x] = Pack(x * 16, 0, 0, 255);
      edge[y * sw + x] = x < sw / 2 ? Pack(0, 0, 0, 255) : Pack(255, 255, 255, 255);
    }
  const auto up = UpscaleCpu(ramp, sw, sh, tw, th, gpu::kUpscaleCatmullRom);
  for (int x = 4; x < tw - 4; ++x) {
    const double expected = ((x + 0.5) * sw / tw - 0.5) * 16.0;
    EXPECT_NEAR(double(up[x] & 0xff), expected, 1.0) << x;
  }
  const auto sharp = UpscaleCpu(edge, sw, sh, tw, th, gpu::kUpscaleCatmullRom);
  const auto soft = UpscaleCpu(edge, sw, sh, tw, th, gpu::kUpscaleBilinear);
  // The pixel just left of the edge: darker than bilinear's (sharper).
  EXPECT_LT(sharp[tw / 2 - 1] & 0xff, soft[tw / 2 - 1] & 0xff);
}

class InteractiveQualityTest : public testing::GpuTest {};

// The floors docs/RENDERING.md ("Interactive quality") gives for the
// phantom, dB.
double InteractivePsnrFloorDb(InteractiveQuality q) {
  switch (q) {
    case InteractiveQuality::kFast:
      return 28.0;
    case InteractiveQuality::kBalanced:
      return 29.5;
    case InteractiveQuality::kSharp:
      return 37.0;
    case InteractiveQuality::kAuto:  // not among the settings tested (kQualities)
      break;
  }
  return 99.0;
}

// Each setting on the GPU is its CPU reference (the same rays, step and
// upscale), through a 96 x 80 frame of the sphere-and-rod volume.
TEST_F(InteractiveQualityTest, EachSetting_GpuMatchesCpuReference) {
  const Volume volume = testing::MakeSphereRodVolume();
  auto gpu_volume = GpuVolume::Upload(context(), volume);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto renderer = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(renderer.ok()) << renderer.status();
  for (InteractiveQuality q : kQualities) {
    RenderRequest r;
    r.camera = Camera::ForVolume(volume.geometry());
    r.camera.Orbit(30.0, 20.0);
    r.preset = *MakeRenderPreset("ct-vessels", volume);
    r.quality = RenderQuality::kInteractive;
    r.interactive = InteractiveCastFor(q);
    r.settings.jitter_seed = 7;
    r.width = 96;
    r.height = 80;
    r.volume = &*gpu_volume;
    auto gpu = (*renderer)->Render(r);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    auto cpu = RenderReference(r, volume, nullptr, 2);
    ASSERT_TRUE(cpu.ok()) << cpu.status();
    EXPECT_EQ(gpu->render_width, q == InteractiveQuality::kSharp ? 96 : 48) << Name(q);
    EXPECT_EQ(gpu->render_height, q == InteractiveQuality::kSharp ? 80 : 40) << Name(q);
    const auto e = CompareRgba(gpu->rgba, cpu->rgba);
    EXPECT_LT(e.mean_abs, 1.0 / 255) << Name(q) << ": max " << e.max_abs * 255 << "/255";
    EXPECT_LT(e.max_abs, 8.0 / 255) << Name(q) << ": mean " << e.mean_abs * 255 << "/255";
  }
}

// The upscale kernel alone (the same ray-cast pixels through both filters):
// GPU against UpscaleCpu within 1/255 for each filter.
TEST_F(InteractiveQualityTest, UpscaleFilters_GpuMatchesCpu) {
  const Volume volume = testing::MakeSphereRodVolume();
  auto gpu_volume = GpuVolume::Upload(context(), volume);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto renderer = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(renderer.ok()) << renderer.status();
  RenderRequest r;
  r.camera = Camera::ForVolume(volume.geometry());
  r.camera.Orbit(30.0, 20.0);
  r.preset = *MakeRenderPreset("ct-vessels", volume);
  r.quality = RenderQuality::kInteractive;
  r.volume = &*gpu_volume;
  r.width = 77;  // odd: the ray grid rounds up
  r.height = 60;
  r.interactive.divisor = 1.0;  // the ray-cast pixels themselves, 39 x 30
  r.width = 39;
  r.height = 30;
  auto small = (*renderer)->Render(r);
  ASSERT_TRUE(small.ok()) << small.status();
  std::vector<uint32_t> pixels(size_t(39) * 30);
  std::memcpy(pixels.data(), small->rgba.data(), small->rgba.size());
  r.width = 77;
  r.height = 60;
  r.interactive.divisor = 2.0;
  for (int filter : {gpu::kUpscaleBilinear, gpu::kUpscaleCatmullRom}) {
    r.interactive.upscale_filter = filter;
    auto frame = (*renderer)->Render(r);
    ASSERT_TRUE(frame.ok()) << frame.status();
    ASSERT_EQ(frame->render_width, 39);
    ASSERT_EQ(frame->render_height, 30);
    const std::vector<uint32_t> cpu = UpscaleCpu(pixels, 39, 30, 77, 60, filter);
    std::vector<uint8_t> cpu_rgba(cpu.size() * 4);
    std::memcpy(cpu_rgba.data(), cpu.data(), cpu_rgba.size());
    EXPECT_LE(CompareRgba(frame->rgba, cpu_rgba).max_abs, 1.0 / 255 + 1e-9) << filter;
  }
}

// Each setting's interactive frame against the still of the same view on
// the phantom (256^3, 512 x 512, default camera, ct-soft-tissue, the frame's
// jitter seed 1): PSNR at least the setting's floor in docs/RENDERING.md
// ("Interactive quality"; measured there during a drag, here undeformed).
TEST_F(InteractiveQualityTest, EachSetting_PhantomPsnrAtLeastItsFloor) {
  auto volume = ReadVolume("phantom:abdomen", VolumeLimits{});
  ASSERT_TRUE(volume.ok()) << volume.status();
  auto gpu_volume = GpuVolume::Upload(context(), *volume);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto renderer = VolumeRenderer::Create(context(), {});
  ASSERT_TRUE(renderer.ok()) << renderer.status();
  RenderRequest r;
  r.camera = Camera::ForVolume(volume->geometry());
  r.preset = *MakeRenderPreset("ct-soft-tissue", *volume);
  r.volume = &*gpu_volume;
  auto still = (*renderer)->Render(r);
  ASSERT_TRUE(still.ok()) << still.status();
  MaybeDump("interactive_quality_still", still->rgba, 512, 512);
  r.quality = RenderQuality::kInteractive;
  r.settings.jitter_seed = 1;
  for (InteractiveQuality q : kQualities) {
    r.interactive = InteractiveCastFor(q);
    auto frame = (*renderer)->Render(r);
    ASSERT_TRUE(frame.ok()) << frame.status();
    MaybeDump(std::string("interactive_quality_") + Name(q), frame->rgba, 512, 512);
    const double psnr = CompareRgba(frame->rgba, still->rgba).psnr_db;
    std::printf("%s: step %.3f mm, %dx%d rays, %.1f dB\n", Name(q), frame->step_mm,
                frame->render_width, frame->render_height, psnr);
    EXPECT_GE(psnr, InteractivePsnrFloorDb(q)) << Name(q);
  }
}

}  // namespace
}  // namespace vpm

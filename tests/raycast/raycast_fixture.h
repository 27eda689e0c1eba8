// The fixture of the ray caster's tests (raycast_test.cc,
// raycast_bands_test.cc): a sphere-and-rod volume on the GPU, a renderer
// with the default options, requests of it, a smooth backward map, and the
// frame comparisons.
#ifndef VPM_TESTS_RAYCAST_RAYCAST_FIXTURE_H_
#define VPM_TESTS_RAYCAST_RAYCAST_FIXTURE_H_

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>

#include <gtest/gtest.h>

#include "server/raycast/raycast_cpu.h"
#include "server/raycast/volume_renderer.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/raycast/render_test_util.h"

namespace vpm::testing {

class RaycastTest : public GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    volume_.emplace(MakeSphereRodVolume());
    auto gpu = GpuVolume::Upload(context(), *volume_);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    gpu_volume_.emplace(std::move(*gpu));
    auto renderer = VolumeRenderer::Create(context(), {});
    ASSERT_TRUE(renderer.ok()) << renderer.status();
    renderer_ = std::move(*renderer);
  }

  RenderRequest Request(RenderMode mode, const char* preset = "ct-vessels", int size = 96) {
    RenderRequest r;
    r.camera = Camera::ForVolume(volume_->geometry());
    r.camera.Orbit(30.0, 20.0);
    r.mode = mode;
    r.preset = *MakeRenderPreset(preset, *volume_);
    r.width = size;
    r.height = size;
    r.volume = &*gpu_volume_;
    return r;
  }

  // A backward map of m^3 points: zero (identity) or a smooth bump, zero
  // on the box faces, up to `amplitude_mm`.
  Result<gpu::GpuImage3D> MakeMap(int m, double amplitude_mm, HostBackwardMap* host) {
    host->dims = {m, m, m};
    host->texels.assign(size_t(m) * m * m, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    for (int c = 0; c < m; ++c)
      for (int b = 0; b < m; ++b)
        for (int a = 0; a < m; ++a) {
          const double s = std::sin(std::numbers::pi * a / (m - 1)) * std::sin(std::numbers::pi * b / (m - 1)) *
                           std::sin(std::numbers::pi * c / (m - 1));
          host->texels[a + m * (b + m * c)] =
              glm::vec4(float(amplitude_mm * s), 0.0f, float(-0.6 * amplitude_mm * s), 1.0f);
        }
    ASSIGN_OR_RETURN(auto image,
                     gpu::GpuImage3D::Create(context(), {uint32_t(m), uint32_t(m), uint32_t(m)},
                                             vk::Format::eR32G32B32A32Sfloat));
    RETURN_IF_ERROR(image.Upload(std::as_bytes(std::span<const glm::vec4>(host->texels))));
    return image;
  }

  Frame RenderGpu(const RenderRequest& r) {
    auto frame = renderer_->Render(r);
    EXPECT_TRUE(frame.ok()) << frame.status();
    return frame.ok() ? std::move(*frame) : Frame{};
  }

  Frame RenderCpu(const RenderRequest& r, const HostBackwardMap* map = nullptr) {
    auto frame = RenderReference(r, *volume_, map, 2);
    EXPECT_TRUE(frame.ok()) << frame.status();
    return frame.ok() ? std::move(*frame) : Frame{};
  }

  std::optional<Volume> volume_;
  std::optional<GpuVolume> gpu_volume_;
  std::unique_ptr<VolumeRenderer> renderer_;
};

inline void ExpectClose(const Frame& a, const Frame& b, double mean_tol, double max_tol,
                 const char* what) {
  ASSERT_EQ(a.rgba.size(), b.rgba.size()) << what;
  const auto e = CompareRgba(a.rgba, b.rgba);
  EXPECT_LT(e.mean_abs, mean_tol) << what << ": max " << e.max_abs * 255 << "/255";
  EXPECT_LT(e.max_abs, max_tol) << what << ": mean " << e.mean_abs * 255 << "/255";
}

// Not a blank frame: some pixels differ from the background by a lot.
inline int64_t LitPixels(const Frame& f) {
  int64_t lit = 0;
  for (size_t i = 0; i < f.rgba.size(); i += 4) lit += (f.rgba[i] + f.rgba[i + 1] + f.rgba[i + 2]) > 60;
  return lit;
}

}  // namespace vpm::testing

#endif  // VPM_TESTS_RAYCAST_RAYCAST_FIXTURE_H_

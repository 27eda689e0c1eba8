// |grad I| on the GPU against the CPU reference, and both against analytic
// values (docs/ALGORITHM.md section 1: central differences, value/mm, clamped).
#include <algorithm>
#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>

#include "server/volume/gradient_magnitude.h"
#include "server/volume/gradient_magnitude_gpu.h"
#include "tests/gpu/gpu_test_context.h"

namespace vpm {
namespace {

using testing::GpuTest;

// dims chosen not to be multiples of the 64-wide workgroup.
Volume MakeTestVolume(std::array<int64_t, 3> dims, glm::dvec3 spacing_mm) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = spacing_mm;
  std::vector<float> values(g.voxel_count());
  uint64_t state = 0x9E3779B97F4A7C15ull;
  for (int64_t k = 0; k < dims[2]; ++k)
    for (int64_t j = 0; j < dims[1]; ++j)
      for (int64_t i = 0; i < dims[0]; ++i) {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        const float noise = static_cast<float>((state >> 40) % 1000) * 0.1f - 50.0f;
        const double r = std::hypot(i - dims[0] / 2.0, j - dims[1] / 2.0, k - dims[2] / 2.0);
        values[i + dims[0] * (j + dims[1] * k)] =
            static_cast<float>((r < dims[0] / 3.0 ? 400.0 : -800.0) + noise);
      }
  return *Volume::Create(g, std::move(values));
}

TEST(GradientMagnitude, MatchesAnalyticRampWithClampedBorders) {
  VolumeGeometry g;
  g.dims = {6, 5, 4};
  g.spacing_mm = {0.5, 2.0, 1.25};
  std::vector<float> values(g.voxel_count());
  // I = 3 value/mm along x, physical coordinate i * sx.
  for (int64_t k = 0; k < 4; ++k)
    for (int64_t j = 0; j < 5; ++j)
      for (int64_t i = 0; i < 6; ++i) values[i + 6 * (j + 5 * k)] = float(3.0 * i * 0.5);
  const Volume v = *Volume::Create(g, values);
  const auto grad = GradientMagnitude(v, 2);
  EXPECT_FLOAT_EQ(grad[v.LinearIndex(2, 2, 2)], 3.0f);
  EXPECT_FLOAT_EQ(grad[v.LinearIndex(0, 1, 1)], 1.5f);  // one-sided at the clamped border
  EXPECT_FLOAT_EQ(grad[v.LinearIndex(5, 4, 3)], 1.5f);
}

TEST(GradientMagnitude, ThreadCountDoesNotChangeResult) {
  const Volume v = MakeTestVolume({21, 17, 13}, {0.7, 0.9, 2.0});
  EXPECT_EQ(GradientMagnitude(v, 1), GradientMagnitude(v, 3));
}

// Tolerance: max |gpu - cpu| / max |cpu| <= 1e-5. Both use float with the
// same differences; the GPU multiplies by 1/(2s) where the CPU divides by 2s,
// which moves results by an ulp or two.
TEST_F(GpuTest, GradientMagnitudeGpu_MatchesCpuReference) {
  const Volume v = MakeTestVolume({37, 29, 23}, {0.8, 1.1, 2.5});
  auto gpu_volume = GpuVolume::Upload(context(), v);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto op = GradientMagnitudeGpu::Create(context());
  ASSERT_TRUE(op.ok()) << op.status();
  auto gpu = op->Run(*gpu_volume);
  ASSERT_TRUE(gpu.ok()) << gpu.status();
  const auto cpu = GradientMagnitude(v, 2);
  ASSERT_EQ(gpu->size(), cpu.size());
  double max_err = 0.0, max_ref = 0.0;
  for (size_t n = 0; n < cpu.size(); ++n) {
    max_err = std::max(max_err, double(std::abs((*gpu)[n] - cpu[n])));
    max_ref = std::max(max_ref, double(std::abs(cpu[n])));
  }
  ASSERT_GT(max_ref, 100.0);
  EXPECT_LE(max_err / max_ref, 1e-5) << "max abs error " << max_err;
}

}  // namespace
}  // namespace vpm

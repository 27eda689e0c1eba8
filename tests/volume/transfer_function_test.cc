// TF(value) of docs/ALGORITHM.md section 1 on the CPU (the contract) and the GPU.
#include <cmath>

#include <gtest/gtest.h>

#include "server/volume/transfer_function.h"
#include "server/volume/transfer_function_gpu.h"
#include "tests/gpu/gpu_test_context.h"

namespace vpm {
namespace {

using testing::GpuTest;

Volume Ramp(int64_t n, float lo, float hi) {
  VolumeGeometry g;
  g.dims = {n, 3, 2};
  std::vector<float> values(g.voxel_count());
  for (size_t i = 0; i < values.size(); ++i) {
    values[i] = lo + (hi - lo) * static_cast<float>(i) / static_cast<float>(values.size() - 1);
  }
  return *Volume::Create(g, values);
}

TEST(TransferFunction, CtSoftTissueMatchesTheSpecPoints) {
  const auto tf = TransferFunction::CtSoftTissue();
  EXPECT_DOUBLE_EQ(tf.Evaluate(-3000), 0.0);   // clamped below
  EXPECT_DOUBLE_EQ(tf.Evaluate(-150), 0.15);   // halfway (-200,0)..(-100,0.3)
  EXPECT_DOUBLE_EQ(tf.Evaluate(20), 0.8);
  EXPECT_DOUBLE_EQ(tf.Evaluate(40), 0.9);
  EXPECT_DOUBLE_EQ(tf.Evaluate(500), 0.75);    // halfway (300,1)..(700,0.5)
  EXPECT_DOUBLE_EQ(tf.Evaluate(5000), 0.5);    // clamped above
}

TEST(TransferFunction, ParsesAndSortsPoints) {
  auto tf = TransferFunction::Parse("100:1, -100:0");
  ASSERT_TRUE(tf.ok()) << tf.status();
  EXPECT_DOUBLE_EQ(tf->Evaluate(0), 0.5);
  EXPECT_EQ(tf->points().front().value, -100);
}

TEST(TransferFunction, RejectsMalformedSpecs) {
  const Volume v = Ramp(4, 0, 1);
  for (const char* bad : {"", "abc", "1:2", "nan:0.5", "1:0.5,2", "ct-unknown", "1:-0.1"}) {
    EXPECT_EQ(TransferFunction::FromSpec(bad, v).status().code(),
              absl::StatusCode::kInvalidArgument)
        << bad;
  }
}

TEST(TransferFunction, MriPresetFollowsTheVolumePercentiles) {
  const Volume v = Ramp(100, 0.0f, 1000.0f);
  auto tf = TransferFunction::FromSpec("mri-t1", v);
  ASSERT_TRUE(tf.ok());
  EXPECT_NEAR(tf->points()[2].value, 500.0, 5.0);  // p50 of a uniform ramp
  EXPECT_DOUBLE_EQ(tf->Evaluate(-1.0), 0.0);
  EXPECT_DOUBLE_EQ(tf->Evaluate(tf->points()[3].value), 1.0);
}

// Tolerance 1e-5 absolute on costs in [0,1]: the GPU evaluates in float.
TEST_F(GpuTest, TransferFunctionGpu_MatchesCpuReference) {
  const Volume v = Ramp(200, -1500.0f, 3500.0f);  // spans every segment and both clamps
  for (const char* preset : {"ct-soft-tissue", "ct-vessels", "ct-bone", "mri-t1"}) {
    auto tf = TransferFunction::FromSpec(preset, v);
    ASSERT_TRUE(tf.ok());
    auto gpu_volume = GpuVolume::Upload(context(), v);
    ASSERT_TRUE(gpu_volume.ok());
    auto op = TransferFunctionGpu::Create(context());
    ASSERT_TRUE(op.ok()) << op.status();
    auto gpu = op->Run(*gpu_volume, *tf);
    ASSERT_TRUE(gpu.ok()) << gpu.status();
    double max_err = 0.0;
    for (size_t n = 0; n < gpu->size(); ++n) {
      max_err = std::max(max_err, std::abs((*gpu)[n] - tf->Evaluate(v.voxels().floats()[n])));
    }
    EXPECT_LE(max_err, 1e-5) << preset;
  }
}

}  // namespace
}  // namespace vpm

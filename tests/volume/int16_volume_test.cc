// Volumes held as int16 + offset (server/volume/voxel_values.h): the values
// read back exactly, the byte budget, and the GPU kernels (gradient, TF)
// reading R32_SINT texels of 2 int16 voxels give the very floats they give for a float
// volume of the same values, and match the CPU reference as before.
#include <cmath>
#include <cstdint>

#include <gtest/gtest.h>

#include "server/volume/gradient_magnitude.h"
#include "server/volume/gradient_magnitude_gpu.h"
#include "server/volume/transfer_function_gpu.h"
#include "tests/gpu/gpu_test_context.h"

namespace vpm {
namespace {

using testing::GpuTest;

// Integer CT-like values (HU), the same volume as int16 + `offset` and as float.
struct TwinVolumes {
  Volume int16;
  Volume floats;
};

TwinVolumes MakeTwins(std::array<int64_t, 3> dims, int32_t offset) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = {0.8, 1.1, 2.5};
  std::vector<int16_t> stored(g.voxel_count());
  std::vector<float> values(g.voxel_count());
  uint64_t state = 0x9E3779B97F4A7C15ull;
  for (int64_t n = 0; n < g.voxel_count(); ++n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t i = n % dims[0], k = n / (dims[0] * dims[1]);
    const int32_t noise = static_cast<int32_t>((state >> 40) % 61) - 30;
    const int32_t value = (i + k < dims[0] ? 300 : -900) + noise + offset;
    stored[n] = static_cast<int16_t>(value - offset);
    values[n] = static_cast<float>(value);
  }
  auto int16 = VoxelValues::Int16(std::move(stored), offset);
  EXPECT_TRUE(int16.ok());
  return {*Volume::Create(g, std::move(*int16)), *Volume::Create(g, std::move(values))};
}

TEST(Int16Volume, ReadsValuesExactlyWithOffset) {
  const TwinVolumes t = MakeTwins({9, 7, 5}, 40000);
  EXPECT_EQ(t.int16.encoding(), VoxelEncoding::kInt16);
  EXPECT_EQ(t.int16.value_bytes(), 9 * 7 * 5 * 2);
  EXPECT_EQ(t.floats.value_bytes(), 9 * 7 * 5 * 4);
  EXPECT_EQ(t.int16.voxels().ToFloats(), t.floats.voxels().ToFloats());
  EXPECT_EQ(t.int16.min_value(), t.floats.min_value());
  EXPECT_EQ(t.int16.max_value(), t.floats.max_value());
  EXPECT_EQ(t.int16.At(8, 6, 4), t.floats.At(8, 6, 4));
  EXPECT_GT(t.int16.max_value(), 32767.0f);  // past int16: the offset carries it
}

TEST(Int16Volume, OffsetKeepsAnyIntegerSpanOf16Bits) {
  EXPECT_EQ(Int16OffsetFor(-1024, 3071), 0);
  EXPECT_EQ(Int16OffsetFor(0, 65535), 32768);  // uint16 MRI
  EXPECT_EQ(Int16OffsetFor(-40000, -40000 + 65535), -40000 + 32768);
  EXPECT_EQ(Int16OffsetFor(0, 65536), std::nullopt);
  EXPECT_EQ(Int16OffsetFor((int64_t{1} << 24) - 10, (int64_t{1} << 24) + 10), std::nullopt);
  EXPECT_FALSE(VoxelValues::Int16({32767}, (1 << 24)).ok());  // 2^24 + 32767: not exact
}

TEST(Int16Volume, BudgetNamesSizeAndBudget) {
  VolumeGeometry g;
  g.dims = {512, 512, 1000};
  // A 512 x 512 x 1,000 int16 CT fits the default budget; as float it does not.
  EXPECT_TRUE(ValidateGeometry(g, VolumeLimits{}, VoxelEncoding::kInt16).ok());
  g.dims = {512, 512, 1100};
  const Status over = ValidateGeometry(g, VolumeLimits{}, VoxelEncoding::kInt16);
  EXPECT_EQ(over.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_NE(over.message().find("512x512x1100 int16"), std::string_view::npos) << over;
  EXPECT_NE(over.message().find(std::to_string(int64_t{512} * 512 * 1100 * 2)),
            std::string_view::npos)
      << over;
  EXPECT_NE(over.message().find(std::to_string(kDefaultMaxVolumeBytes)), std::string_view::npos)
      << over;
  EXPECT_NE(over.message().find("--max-volume-bytes"), std::string_view::npos) << over;
  g.dims = {512, 512, 1000};
  EXPECT_EQ(ValidateGeometry(g, VolumeLimits{}, VoxelEncoding::kFloat32).code(),
            absl::StatusCode::kResourceExhausted);
}

TEST(Int16Volume, CpuGradientEqualsFloatVolumes) {
  const TwinVolumes t = MakeTwins({21, 17, 13}, 0);
  EXPECT_EQ(GradientMagnitude(t.int16, 2), GradientMagnitude(t.floats, 2));
}

// The GPU reads int16 voxels in pairs (R32_SINT texels of voxels n and
// n + 1) or packed (2 voxels per texel), floats in pairs (R32G32_SINT): all
// decode to the same floats, so the outputs are bit-equal, and within the
// float tolerance (1e-5 of the largest) of the CPU reference.
TEST_F(GpuTest, GradientMagnitudeGpu_Int16EqualsFloatAndCpu) {
  for (int32_t offset : {0, 40000}) {
    const TwinVolumes t = MakeTwins({37, 29, 23}, offset);  // 24679 voxels: odd
    auto op = GradientMagnitudeGpu::Create(context());
    ASSERT_TRUE(op.ok()) << op.status();
    auto gpu16 = GpuVolume::Upload(context(), t.int16);
    auto packed = GpuVolume::Upload(context(), t.int16, {}, GpuVolume::TexelLayout::kPacked);
    auto gpu32 = GpuVolume::Upload(context(), t.floats);
    ASSERT_TRUE(gpu16.ok() && packed.ok() && gpu32.ok());
    EXPECT_EQ(gpu16->layout(), GpuVolume::TexelLayout::kPairs);
    EXPECT_EQ(gpu16->buffer_bytes(), 24679 * 4);
    EXPECT_EQ(packed->buffer_bytes(), (24679 + 1) / 2 * 4);
    EXPECT_EQ(gpu32->buffer_bytes(), 24679 * 8);
    const uint64_t limit = context().limits().maxTexelBufferElements;
    EXPECT_EQ(gpu16->buffer_bytes(),
              int64_t(GpuVolume::BufferBytesFor(VoxelEncoding::kInt16, 24679, limit)));
    EXPECT_EQ(gpu32->buffer_bytes(),
              int64_t(GpuVolume::BufferBytesFor(VoxelEncoding::kFloat32, 24679, limit)));
    auto a = op->Run(*gpu16);
    auto b = op->Run(*gpu32);
    auto c = op->Run(*packed);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok()) << a.status() << b.status() << c.status();
    EXPECT_EQ(*a, *b) << "offset " << offset;
    EXPECT_EQ(*a, *c) << "offset " << offset;
    const auto cpu = GradientMagnitude(t.int16, 2);
    double max_err = 0.0, max_ref = 0.0;
    for (size_t n = 0; n < cpu.size(); ++n) {
      max_err = std::max(max_err, double(std::abs((*a)[n] - cpu[n])));
      max_ref = std::max(max_ref, double(std::abs(cpu[n])));
    }
    ASSERT_GT(max_ref, 100.0);
    EXPECT_LE(max_err / max_ref, 1e-5) << "max abs error " << max_err;
  }
}

// The pairs as the device holds them, read back, over more than one
// upload slab (16 MiB: 4 Mi int16 texels, 2 Mi float texels) and an odd
// voxel count: texel n is voxel n and voxel n + 1 (0 past the last).
TEST_F(GpuTest, GpuVolume_PairsHoldEachVoxelAndItsNextAcrossSlabs) {
  const TwinVolumes t =
      MakeTwins({257, 131, 139}, 0);  // 4,679,713 voxels: odd; 2 int16 slabs, 3 float
  const int64_t voxels = t.int16.geometry().voxel_count();
  const std::span<const int16_t> s = t.int16.voxels().int16s();
  auto gpu16 = GpuVolume::Upload(context(), t.int16);
  ASSERT_TRUE(gpu16.ok()) << gpu16.status();
  std::vector<uint32_t> words(voxels);
  ASSERT_TRUE(gpu16->buffer().DownloadSpan(std::span<uint32_t>(words)).ok());
  for (int64_t n = 0; n < voxels; ++n) {
    const uint32_t high = n + 1 < voxels ? uint16_t(s[n + 1]) : 0u;
    ASSERT_EQ(words[n], uint32_t(uint16_t(s[n])) | (high << 16)) << "int16 texel " << n;
  }
  const std::span<const float> f = t.floats.voxels().floats();
  auto gpu32 = GpuVolume::Upload(context(), t.floats);
  ASSERT_TRUE(gpu32.ok()) << gpu32.status();
  std::vector<float> pairs(2 * voxels);
  ASSERT_TRUE(gpu32->buffer().DownloadSpan(std::span<float>(pairs)).ok());
  for (int64_t n = 0; n < voxels; ++n) {
    ASSERT_EQ(pairs[2 * n], f[n]) << "float texel " << n;
    ASSERT_EQ(pairs[2 * n + 1], n + 1 < voxels ? f[n + 1] : 0.0f) << "float texel " << n;
  }
}

TEST_F(GpuTest, TransferFunctionGpu_Int16MatchesCpuPerVoxel) {
  const TwinVolumes t = MakeTwins({33, 19, 11}, -20000);
  const TransferFunction tf =
      *TransferFunction::Create({{-21000, 0.0}, {-20900, 0.4}, {-19800, 1.0}, {-19600, 0.2}});
  auto op = TransferFunctionGpu::Create(context());
  ASSERT_TRUE(op.ok()) << op.status();
  auto gpu_volume = GpuVolume::Upload(context(), t.int16);
  ASSERT_TRUE(gpu_volume.ok()) << gpu_volume.status();
  auto gpu = op->Run(*gpu_volume, tf);
  ASSERT_TRUE(gpu.ok()) << gpu.status();
  double max_err = 0.0;
  for (int64_t n = 0; n < t.int16.geometry().voxel_count(); ++n) {
    max_err = std::max(max_err, std::abs(double((*gpu)[n]) - tf.Evaluate(t.int16.voxels()[n])));
  }
  EXPECT_LE(max_err, 1e-5);
}

// Pairs wherever the limit holds one texel per voxel; past it int16
// volumes pack 2 voxels per texel and float volumes do not fit.
TEST(GpuVolumeLayout, PairsWhereTheyFitElsePackedInt16) {
  using L = GpuVolume::TexelLayout;
  const uint64_t limit = uint64_t{1} << 27;
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kInt16, limit, limit), L::kPairs);
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kFloat32, limit, limit), L::kPairs);
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kInt16, limit + 1, limit), L::kPacked);
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kInt16, 2 * limit, limit), L::kPacked);
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kInt16, 2 * limit + 1, limit), std::nullopt);
  EXPECT_EQ(GpuVolume::LayoutFor(VoxelEncoding::kFloat32, limit + 1, limit), std::nullopt);
  EXPECT_EQ(GpuVolume::BufferBytesFor(VoxelEncoding::kInt16, limit, limit), limit * 4);
  EXPECT_EQ(GpuVolume::BufferBytesFor(VoxelEncoding::kInt16, limit + 1, limit),
            (limit + 2) / 2 * 4);
  EXPECT_EQ(GpuVolume::BufferBytesFor(VoxelEncoding::kFloat32, limit, limit), limit * 8);
  EXPECT_EQ(GpuVolume::BufferBytesFor(VoxelEncoding::kFloat32, limit + 1, limit), 0u);
}

// A cancelled upload returns the token's status and keeps nothing.
TEST_F(GpuTest, GpuVolume_UploadStopsWhenCancelled) {
  const TwinVolumes t = MakeTwins({5, 4, 3}, 0);
  CancelToken::Source source;
  source.Cancel();
  auto uploaded = GpuVolume::Upload(context(), t.int16, {}, std::nullopt, source.token());
  EXPECT_EQ(uploaded.status().code(), absl::StatusCode::kCancelled) << uploaded.status();
}

// A float volume cannot be packed: a clear error, not a wrong read.
TEST_F(GpuTest, GpuVolume_FloatPackedRefused) {
  const TwinVolumes t = MakeTwins({5, 4, 3}, 0);
  auto packed = GpuVolume::Upload(context(), t.floats, {}, GpuVolume::TexelLayout::kPacked);
  EXPECT_EQ(packed.status().code(), absl::StatusCode::kInvalidArgument) << packed.status();
}

}  // namespace
}  // namespace vpm

// The Vulkan compute core: buffers and 3D images round-trip, and a dispatch
// refuses to record when its invariants do not hold.
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "server/gpu/compute_batch.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_image3d.h"
#include "server/gpu/shader_interface.h"
#include "shaders/gradient_magnitude.spv.h"
#include "tests/gpu/gpu_test_context.h"

namespace vpm {
namespace {

using testing::GpuTest;

TEST_F(GpuTest, GpuBuffer_RoundTripsBytesAtAnOffset) {
  auto buffer = gpu::GpuBuffer::Create(context(), 4096, vk::BufferUsageFlagBits::eStorageBuffer);
  ASSERT_TRUE(buffer.ok()) << buffer.status();
  std::vector<uint32_t> in(256);
  std::iota(in.begin(), in.end(), 7u);
  ASSERT_TRUE(buffer->UploadSpan(std::span<const uint32_t>(in)).ok());
  std::vector<uint32_t> out(256);
  ASSERT_TRUE(buffer->DownloadSpan(std::span<uint32_t>(out)).ok());
  EXPECT_EQ(in, out);
  const std::vector<std::byte> tail(16, std::byte{0xAB});
  ASSERT_TRUE(buffer->Upload(tail, 4080).ok());
  std::vector<std::byte> back(16);
  ASSERT_TRUE(buffer->Download(back, 4080).ok());
  EXPECT_EQ(back, tail);
}

// Fill hands out exactly the range asked for, and what it writes there is
// what a download reads back; the bytes around it stay as they were.
TEST_F(GpuTest, GpuBuffer_FillWritesTheRangeInPlace) {
  auto buffer = gpu::GpuBuffer::Create(context(), 256, vk::BufferUsageFlagBits::eStorageBuffer);
  ASSERT_TRUE(buffer.ok()) << buffer.status();
  const std::vector<std::byte> zeros(256, std::byte{0});
  ASSERT_TRUE(buffer->Upload(zeros).ok());
  size_t handed = 0;
  ASSERT_TRUE(buffer
                  ->Fill(100, 40,
                         [&](std::span<std::byte> b) {
                           handed = b.size();
                           for (size_t i = 0; i < b.size(); ++i) b[i] = std::byte(i + 1);
                         })
                  .ok());
  EXPECT_EQ(handed, 40u);
  std::vector<std::byte> back(256);
  ASSERT_TRUE(buffer->Download(back).ok());
  for (size_t i = 0; i < back.size(); ++i) {
    const std::byte want = i >= 100 && i < 140 ? std::byte(i - 99) : std::byte{0};
    ASSERT_EQ(back[i], want) << "byte " << i;
  }
  bool called = false;
  EXPECT_EQ(buffer->Fill(250, 8, [&](std::span<std::byte>) { called = true; }).code(),
            absl::StatusCode::kOutOfRange);
  EXPECT_FALSE(called);
}

TEST_F(GpuTest, GpuBuffer_RejectsOutOfRangeAccess) {
  auto buffer = gpu::GpuBuffer::Create(context(), 64, vk::BufferUsageFlagBits::eStorageBuffer);
  ASSERT_TRUE(buffer.ok());
  std::vector<std::byte> data(32);
  EXPECT_EQ(buffer->Upload(data, 40).code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(buffer->Download(data, 65).code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(
      gpu::GpuBuffer::Create(context(), 0, vk::BufferUsageFlagBits::eStorageBuffer).status().code(),
      absl::StatusCode::kInvalidArgument);
}

TEST_F(GpuTest, GpuImage3D_RoundTripsTexels) {
  auto image = gpu::GpuImage3D::Create(context(), {13, 7, 5}, vk::Format::eR32Sfloat);
  ASSERT_TRUE(image.ok()) << image.status();
  std::vector<float> in(13 * 7 * 5);
  for (size_t n = 0; n < in.size(); ++n) in[n] = static_cast<float>(n) * 0.25f - 30.0f;
  ASSERT_TRUE(image->Upload(std::as_bytes(std::span(in))).ok());
  std::vector<float> out(in.size());
  ASSERT_TRUE(image->Download(std::as_writable_bytes(std::span(out))).ok());
  EXPECT_EQ(in, out);
  EXPECT_EQ(image->Upload(std::as_bytes(std::span(in).subspan(1))).code(),
            absl::StatusCode::kInvalidArgument);
}

// A box of a buffer (rows of the image's width) lands at the box in the
// image; the texels outside it keep their values.
TEST_F(GpuTest, ComputeBatch_CopyBufferToImageWritesTheBoxOnly) {
  const std::array<uint32_t, 3> e = {13, 7, 5};
  auto image = gpu::GpuImage3D::Create(context(), e, vk::Format::eR32Sfloat);
  ASSERT_TRUE(image.ok()) << image.status();
  std::vector<float> before(e[0] * e[1] * e[2]);
  for (size_t n = 0; n < before.size(); ++n) before[n] = -1.0f - static_cast<float>(n);
  ASSERT_TRUE(image->Upload(std::as_bytes(std::span(before))).ok());
  std::vector<float> source(before.size());
  std::iota(source.begin(), source.end(), 100.0f);
  auto buffer = gpu::GpuBuffer::Create(context(), source.size() * sizeof(float),
                                       vk::BufferUsageFlagBits::eStorageBuffer);
  ASSERT_TRUE(buffer.ok()) << buffer.status();
  ASSERT_TRUE(buffer->UploadSpan(std::span<const float>(source)).ok());
  const glm::ivec3 lo(2, 1, 1), size(5, 4, 3);
  const size_t first = lo.x + e[0] * (lo.y + e[1] * lo.z);
  const std::pair<const gpu::GpuBuffer*, vk::BufferImageCopy> region{
      &*buffer, vk::BufferImageCopy(first * sizeof(float), e[0], e[1],
                                    {vk::ImageAspectFlagBits::eColor, 0, 0, 1}, {lo.x, lo.y, lo.z},
                                    {uint32_t(size.x), uint32_t(size.y), uint32_t(size.z)})};
  auto batch = gpu::ComputeBatch::Begin(context(), 1);
  ASSERT_TRUE(batch.ok());
  ASSERT_TRUE(batch->CopyBufferToImage(std::span(&region, 1), *image, "copy").ok());
  auto timings = batch->SubmitAndWait();
  ASSERT_TRUE(timings.ok()) << timings.status();
  ASSERT_EQ(timings->size(), 1u);
  EXPECT_EQ((*timings)[0].label, "copy");
  std::vector<float> after(before.size());
  ASSERT_TRUE(image->Download(std::as_writable_bytes(std::span(after))).ok());
  for (uint32_t z = 0; z < e[2]; ++z) {
    for (uint32_t y = 0; y < e[1]; ++y) {
      for (uint32_t x = 0; x < e[0]; ++x) {
        const size_t n = x + e[0] * (y + e[1] * z);
        const glm::ivec3 p(x, y, z);
        const bool inside =
            glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThan(p, lo + size));
        EXPECT_EQ(after[n], inside ? source[n] : before[n]) << x << " " << y << " " << z;
      }
    }
  }
}

TEST_F(GpuTest, GpuImage3D_RejectsAbsurdExtent) {
  EXPECT_EQ(gpu::GpuImage3D::Create(context(), {0, 4, 4}, vk::Format::eR32Sfloat).status().code(),
            absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(
      gpu::GpuImage3D::Create(context(), {1u << 20, 4, 4}, vk::Format::eR32Sfloat).status().code(),
      absl::StatusCode::kResourceExhausted);
}

class ComputeBatchTest : public GpuTest {
 protected:
  void SetUp() override {
    GpuTest::SetUp();
    auto kernel = gpu::ComputeKernel::Create(
        context(),
        {.name = "gradient_magnitude",
         .spirv = kGradientMagnitudeSpv,
         .bindings = {vk::DescriptorType::eUniformTexelBuffer, vk::DescriptorType::eStorageBuffer},
         .push_constant_bytes = sizeof(gpu::GradientPush),
         .local_size = {64, 1, 1}});
    ASSERT_TRUE(kernel.ok()) << kernel.status();
    kernel_.emplace(std::move(*kernel));
    auto volume = gpu::GpuBuffer::Create(context(), 8 * 8 * 8 * 4,
                                         vk::BufferUsageFlagBits::eUniformTexelBuffer);
    auto out =
        gpu::GpuBuffer::Create(context(), 8 * 8 * 8 * 4, vk::BufferUsageFlagBits::eStorageBuffer);
    auto ubo = gpu::GpuBuffer::Create(context(), 256, vk::BufferUsageFlagBits::eUniformBuffer);
    ASSERT_TRUE(volume.ok() && out.ok() && ubo.ok());
    volume_.emplace(std::move(*volume));
    out_.emplace(std::move(*out));
    ubo_.emplace(std::move(*ubo));
    view_ = vk::raii::BufferView(
        context().device(),
        vk::BufferViewCreateInfo({}, volume_->handle(), vk::Format::eR32Sint, 0, VK_WHOLE_SIZE));
    texels_ = *view_;
  }
  std::optional<gpu::ComputeKernel> kernel_;
  std::optional<gpu::GpuBuffer> volume_, out_, ubo_;
  vk::raii::BufferView view_{nullptr};
  vk::BufferView texels_;
  gpu::GradientPush push_{.dims = glm::ivec4(8, 8, 8, 0), .inv_two_spacing = glm::vec4(0.5f)};
};

TEST_F(ComputeBatchTest, ComputeKernel_RejectsMissingSpirvAndBadLocalSize) {
  EXPECT_EQ(gpu::ComputeKernel::Create(context(), {.name = "empty"}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(gpu::ComputeKernel::Create(
                context(),
                {.name = "huge", .spirv = kGradientMagnitudeSpv, .local_size = {1u << 20, 1, 1}})
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(
      gpu::ComputeKernel::Create(
          context(), {.name = "odd push", .spirv = kGradientMagnitudeSpv, .push_constant_bytes = 6})
          .status()
          .code(),
      absl::StatusCode::kInvalidArgument);
}

TEST_F(ComputeBatchTest, ComputeKernel_SameSpecSharesOnePipeline) {
  const gpu::KernelSpec spec{
      .name = "gradient_magnitude",
      .spirv = kGradientMagnitudeSpv,
      .bindings = {vk::DescriptorType::eUniformTexelBuffer, vk::DescriptorType::eStorageBuffer},
      .push_constant_bytes = sizeof(gpu::GradientPush),
      .local_size = {64, 1, 1}};
  const size_t cached = context().pipelines().size();
  auto again = gpu::ComputeKernel::Create(context(), spec);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->pipeline(), kernel_->pipeline());
  EXPECT_EQ(context().pipelines().size(), cached);
  // Another specialization (or local size) is another pipeline.
  gpu::KernelSpec other = spec;
  other.specialization = {1};
  auto specialized = gpu::ComputeKernel::Create(context(), other);
  ASSERT_TRUE(specialized.ok()) << specialized.status();
  EXPECT_NE(specialized->pipeline(), kernel_->pipeline());
  EXPECT_EQ(context().pipelines().size(), cached + 1);
}

TEST_F(ComputeBatchTest, Dispatch_RejectsWrongBindingCountAndKinds) {
  auto batch = gpu::ComputeBatch::Begin(context(), 4);
  ASSERT_TRUE(batch.ok());
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_}, push_, {1, 8, 8}).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(batch->Dispatch(*kernel_, {&*out_, &*out_}, push_, {1, 8, 8}).code(),
            absl::StatusCode::kInvalidArgument);
  // A uniform buffer where the kernel writes a storage buffer.
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*ubo_}, push_, {1, 8, 8}).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(batch->SubmitAndWait().ok());
}

TEST_F(ComputeBatchTest, Dispatch_RejectsWrongPushSizeAndGroupCounts) {
  auto batch = gpu::ComputeBatch::Begin(context(), 4);
  ASSERT_TRUE(batch.ok());
  const gpu::VoxelMapPush short_push{};
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*out_}, short_push, {1, 8, 8}).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {0, 8, 8}).code(),
            absl::StatusCode::kInvalidArgument);
  const uint32_t too_many = context().limits().maxComputeWorkGroupCount[1] + 1;
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {1, too_many, 1}).code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(batch->SubmitAndWait().ok());
}

TEST_F(ComputeBatchTest, Batch_CapsDispatchesAndSubmitsOnce) {
  auto batch = gpu::ComputeBatch::Begin(context(), 2);
  ASSERT_TRUE(batch.ok());
  EXPECT_TRUE(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {1, 8, 8}, "a").ok());
  EXPECT_TRUE(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {1, 8, 8}, "b").ok());
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {1, 8, 8}).code(),
            absl::StatusCode::kResourceExhausted);
  auto timings = batch->SubmitAndWait();
  ASSERT_TRUE(timings.ok()) << timings.status();
  ASSERT_EQ(timings->size(), 2u);
  EXPECT_EQ((*timings)[0].label, "a");
  if (context().timestamp_period_ns() > 0) {
    EXPECT_GE((*timings)[1].gpu_ms, 0.0);
  }
  EXPECT_EQ(batch->SubmitAndWait().status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(batch->Dispatch(*kernel_, {texels_, &*out_}, push_, {1, 8, 8}).code(),
            absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace vpm

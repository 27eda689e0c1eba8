#include "server/gpu/gpu_image3d.h"

#include "server/gpu/gpu_buffer.h"

namespace vpm::gpu {
namespace {

size_t TexelBytes(vk::Format format) {
  switch (format) {
    case vk::Format::eR32Sfloat: return 4;
    case vk::Format::eR16Unorm:
    case vk::Format::eR16Sfloat: return 2;
    case vk::Format::eR8Unorm: return 1;
    case vk::Format::eR8G8B8A8Unorm: return 4;
    case vk::Format::eR32G32B32A32Sfloat: return 16;
    default: return 0;
  }
}

const vk::ImageSubresourceRange kColorRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1);
const vk::ImageSubresourceLayers kColorLayers(vk::ImageAspectFlagBits::eColor, 0, 0, 1);

// A layout change with a full barrier on either side: uploads and readbacks
// are rare and whole-image, so precision in the stage masks buys nothing.
void Transition(const vk::raii::CommandBuffer& cmd, vk::Image image, vk::ImageLayout from,
                vk::ImageLayout to) {
  const auto all = vk::AccessFlagBits::eMemoryRead | vk::AccessFlagBits::eMemoryWrite;
  vk::ImageMemoryBarrier barrier(all, all, from, to, VK_QUEUE_FAMILY_IGNORED,
                                 VK_QUEUE_FAMILY_IGNORED, image, kColorRange);
  cmd.pipelineBarrier(vk::PipelineStageFlagBits::eAllCommands,
                      vk::PipelineStageFlagBits::eAllCommands, {}, {}, {}, barrier);
}

}  // namespace

Result<GpuImage3D> GpuImage3D::Create(const GpuContext& context, std::array<uint32_t, 3> extent,
                                      vk::Format format) {
  GpuImage3D img;
  img.context_ = &context;
  img.extent_ = extent;
  img.format_ = format;
  img.texel_bytes_ = TexelBytes(format);
  if (img.texel_bytes_ == 0) {
    return absl::InvalidArgumentError(
        StrCat("unsupported 3D image format ", vk::to_string(format)));
  }
  const uint32_t max_dim = context.limits().maxImageDimension3D;
  for (uint32_t e : extent) {
    if (e == 0 || e > max_dim) {
      return absl::ResourceExhaustedError(StrCat(
          "3D image of ", extent[0], "x", extent[1], "x", extent[2],
          " texels: each side must be in 1..", max_dim, " on this device"));
    }
  }
  const auto features = context.physical_device().getFormatProperties(format).optimalTilingFeatures;
  vk::ImageUsageFlags usage = vk::ImageUsageFlagBits::eSampled |
                              vk::ImageUsageFlagBits::eTransferDst |
                              vk::ImageUsageFlagBits::eTransferSrc;
  if (features & vk::FormatFeatureFlagBits::eStorageImage) {
    usage |= vk::ImageUsageFlagBits::eStorage;
  }
  const bool linear = static_cast<bool>(
      features & vk::FormatFeatureFlagBits::eSampledImageFilterLinear);
  RETURN_IF_ERROR(CatchVulkan("creating a 3D image", [&] {
    vk::ImageCreateInfo info({}, vk::ImageType::e3D, format,
                             vk::Extent3D(extent[0], extent[1], extent[2]), 1, 1,
                             vk::SampleCountFlagBits::e1, vk::ImageTiling::eOptimal, usage,
                             vk::SharingMode::eExclusive, {}, vk::ImageLayout::eUndefined);
    img.image_ = vk::raii::Image(context.device(), info);
  }));
  const vk::MemoryRequirements req = img.image_.getMemoryRequirements();
  ASSIGN_OR_RETURN(const uint32_t type,
                   context.FindMemoryType(req.memoryTypeBits,
                                          vk::MemoryPropertyFlagBits::eDeviceLocal, {}));
  RETURN_IF_ERROR(CatchVulkan("allocating 3D image memory", [&] {
    img.memory_ = vk::raii::DeviceMemory(context.device(), vk::MemoryAllocateInfo(req.size, type));
    img.image_.bindMemory(*img.memory_, 0);
    img.view_ = vk::raii::ImageView(
        context.device(),
        vk::ImageViewCreateInfo({}, *img.image_, vk::ImageViewType::e3D, format, {}, kColorRange));
    const vk::Filter filter = linear ? vk::Filter::eLinear : vk::Filter::eNearest;
    vk::SamplerCreateInfo sampler_info(
        {}, filter, filter, vk::SamplerMipmapMode::eNearest, vk::SamplerAddressMode::eClampToEdge,
        vk::SamplerAddressMode::eClampToEdge, vk::SamplerAddressMode::eClampToEdge);
    img.sampler_ = vk::raii::Sampler(context.device(), sampler_info);
  }));
  RETURN_IF_ERROR(context.RunCommands([&](const vk::raii::CommandBuffer& cmd) {
    vk::ImageMemoryBarrier barrier({}, vk::AccessFlagBits::eShaderRead |
                                           vk::AccessFlagBits::eShaderWrite |
                                           vk::AccessFlagBits::eTransferWrite,
                                   vk::ImageLayout::eUndefined, vk::ImageLayout::eGeneral,
                                   VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                                   *img.image_, kColorRange);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTopOfPipe,
                        vk::PipelineStageFlagBits::eAllCommands, {}, {}, {}, barrier);
  }));
  return img;
}

Status GpuImage3D::CheckSize(size_t bytes) const {
  if (bytes != size_bytes()) {
    return absl::InvalidArgumentError(StrCat("3D image transfer of ", bytes,
                                                   " bytes; the image holds ", size_bytes()));
  }
  return absl::OkStatus();
}

Status GpuImage3D::Upload(std::span<const std::byte> texels) {
  RETURN_IF_ERROR(CheckSize(texels.size()));
  ASSIGN_OR_RETURN(GpuBuffer staging, GpuBuffer::CreateStaging(*context_, texels.size()));
  RETURN_IF_ERROR(staging.Upload(texels));
  return context_->RunCommands([&](const vk::raii::CommandBuffer& cmd) {
    vk::BufferImageCopy region(0, 0, 0, kColorLayers, {0, 0, 0},
                               vk::Extent3D(extent_[0], extent_[1], extent_[2]));
    constexpr auto kDst = vk::ImageLayout::eTransferDstOptimal;
    Transition(cmd, *image_, vk::ImageLayout::eGeneral, kDst);
    cmd.copyBufferToImage(staging.handle(), *image_, kDst, region);
    Transition(cmd, *image_, kDst, vk::ImageLayout::eGeneral);
  });
}

Status GpuImage3D::Download(std::span<std::byte> texels) const {
  RETURN_IF_ERROR(CheckSize(texels.size()));
  ASSIGN_OR_RETURN(GpuBuffer staging, GpuBuffer::CreateStaging(*context_, texels.size()));
  RETURN_IF_ERROR(context_->RunCommands([&](const vk::raii::CommandBuffer& cmd) {
    vk::BufferImageCopy region(0, 0, 0, kColorLayers, {0, 0, 0},
                               vk::Extent3D(extent_[0], extent_[1], extent_[2]));
    constexpr auto kSrc = vk::ImageLayout::eTransferSrcOptimal;
    Transition(cmd, *image_, vk::ImageLayout::eGeneral, kSrc);
    cmd.copyImageToBuffer(*image_, kSrc, staging.handle(), region);
    Transition(cmd, *image_, kSrc, vk::ImageLayout::eGeneral);
    vk::MemoryBarrier after(vk::AccessFlagBits::eTransferWrite, vk::AccessFlagBits::eHostRead);
    cmd.pipelineBarrier(vk::PipelineStageFlagBits::eTransfer, vk::PipelineStageFlagBits::eHost,
                        {}, after, {}, {});
  }));
  return staging.Download(texels);
}

}  // namespace vpm::gpu

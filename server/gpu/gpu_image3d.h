// A 3D image (a volume on the GPU) with its view and a trilinear sampler,
// kept in VK_IMAGE_LAYOUT_GENERAL so that one image serves as sampled image,
// storage image and transfer source or destination without layout tracking.
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"
#include "server/gpu/gpu_context.h"

namespace vpm::gpu {

class GpuImage3D {
 public:
  // extent: (width, height, depth) texels. Supported formats: R32Sfloat,
  // R16Unorm, R16Sfloat, R8Unorm, R8G8B8A8Unorm, R32G32B32A32Sfloat.
  static Result<GpuImage3D> Create(const GpuContext& context, std::array<uint32_t, 3> extent,
                                   vk::Format format);

  GpuImage3D(GpuImage3D&&) = default;
  GpuImage3D& operator=(GpuImage3D&&) = default;

  // Tightly packed texels, x fastest; size must be width*height*depth*texel_bytes.
  Status Upload(std::span<const std::byte> texels);
  Status Download(std::span<std::byte> texels) const;

  vk::Image image() const { return *image_; }
  vk::ImageView view() const { return *view_; }
  // Clamp-to-edge, linear filtering, unnormalised=false (coordinates in [0,1]).
  vk::Sampler linear_sampler() const { return *sampler_; }
  vk::Format format() const { return format_; }
  const std::array<uint32_t, 3>& extent() const { return extent_; }
  size_t texel_bytes() const { return texel_bytes_; }
  size_t size_bytes() const {
    return size_t{extent_[0]} * extent_[1] * extent_[2] * texel_bytes_;
  }

 private:
  GpuImage3D() = default;
  Status CheckSize(size_t bytes) const;

  const GpuContext* context_ = nullptr;
  vk::raii::Image image_{nullptr};
  vk::raii::DeviceMemory memory_{nullptr};
  vk::raii::ImageView view_{nullptr};
  vk::raii::Sampler sampler_{nullptr};
  std::array<uint32_t, 3> extent_{0, 0, 0};
  vk::Format format_ = vk::Format::eUndefined;
  size_t texel_bytes_ = 0;
};

}  // namespace vpm::gpu

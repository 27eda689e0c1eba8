#include "server/volume/gpu_volume.h"

#include <algorithm>
#include <bit>

namespace vpm {
namespace {

// Uploads go in slabs of this many bytes, so that a device without
// host-visible memory needs a staging buffer of one slab, not of the volume,
// and a cancelled load stops within a slab's time (milliseconds).
constexpr int64_t kUploadSlabBytes = int64_t{16} << 20;

// Texels of a volume of `voxels` in `layout`: one per voxel in pairs, one
// per 2 packed.
uint64_t TexelsFor(GpuVolume::TexelLayout layout, uint64_t voxels) {
  return layout == GpuVolume::TexelLayout::kPairs ? voxels : (voxels + 1) / 2;
}

// The texel format of `layout`: float pairs need two 32-bit channels.
vk::Format TexelFormat(VoxelEncoding encoding, GpuVolume::TexelLayout layout) {
  return layout == GpuVolume::TexelLayout::kPairs && encoding == VoxelEncoding::kFloat32
             ? vk::Format::eR32G32Sint
             : vk::Format::eR32Sint;
}

uint64_t TexelBytes(vk::Format format) { return format == vk::Format::eR32G32Sint ? 8 : 4; }

// Texels [first, first + count) of the pairs layout into `words`: one
// word per texel for int16 (voxel n in the low half, n + 1 in the high),
// two for float (the bits of n, then of n + 1). The voxel past the last
// reads 0. Every word is written (words is device memory, not zeroed).
void WritePairTexels(const VoxelValues& values, uint64_t first, uint64_t count,
                     std::span<uint32_t> words) {
  // Texels whose n + 1 exists (their loop tests nothing), then the last.
  const uint64_t last = uint64_t(values.size()) - 1;
  const uint64_t full = std::min(count, last - std::min(first, last));
  if (const std::span<const int16_t> s = values.int16s(); !s.empty()) {
    const int16_t* v = s.data() + first;
    for (uint64_t i = 0; i < full; ++i) {
      words[i] = uint32_t(uint16_t(v[i])) | (uint32_t(uint16_t(v[i + 1])) << 16);
    }
    for (uint64_t i = full; i < count; ++i) words[i] = uint32_t(uint16_t(v[i]));
    return;
  }
  const float* v = values.floats().data() + first;
  for (uint64_t i = 0; i < full; ++i) {
    words[2 * i] = std::bit_cast<uint32_t>(v[i]);
    words[2 * i + 1] = std::bit_cast<uint32_t>(v[i + 1]);
  }
  for (uint64_t i = full; i < count; ++i) {
    words[2 * i] = std::bit_cast<uint32_t>(v[i]);
    words[2 * i + 1] = 0u;
  }
}

// Uploads the values, in pairs or packed, into `buffer`, in slabs of
// kUploadSlabBytes: pairs written slab by slab straight into the buffer's
// mapping (WritePairTexels), packed int16s as the host holds them (an odd
// count leaves the last texel's high half unset: never read).
Status UploadTexels(gpu::GpuBuffer& buffer, const VoxelValues& values, bool pairs,
                    uint64_t texel_bytes, const ProgressFn& progress, const CancelToken& cancel) {
  if (!pairs) {
    const std::span<const std::byte> bytes = values.bytes();
    for (size_t offset = 0; offset < bytes.size(); offset += kUploadSlabBytes) {
      RETURN_IF_ERROR(cancel.Check());
      const size_t n = std::min<size_t>(kUploadSlabBytes, bytes.size() - offset);
      RETURN_IF_ERROR(buffer.Upload(bytes.subspan(offset, n), offset));
      if (progress) progress(double(offset + n) / double(bytes.size()), "uploading");
    }
    return absl::OkStatus();
  }
  const uint64_t texels = values.size();
  const uint64_t slab_texels = uint64_t(kUploadSlabBytes) / texel_bytes;
  for (uint64_t first = 0; first < texels; first += slab_texels) {
    RETURN_IF_ERROR(cancel.Check());
    const uint64_t n = std::min(slab_texels, texels - first);
    RETURN_IF_ERROR(buffer.Fill(first * texel_bytes, n * texel_bytes, [&](std::span<std::byte> b) {
      // Device and staging mappings are aligned far beyond 4 bytes.
      WritePairTexels(values, first, n,
                      std::span<uint32_t>(reinterpret_cast<uint32_t*>(b.data()), b.size() / 4));
    }));
    if (progress) progress(double(first + n) / double(texels), "uploading");
  }
  return absl::OkStatus();
}

}  // namespace

std::optional<GpuVolume::TexelLayout> GpuVolume::LayoutFor(VoxelEncoding encoding, uint64_t voxels,
                                                           uint64_t max_texels) {
  if (voxels <= max_texels) return TexelLayout::kPairs;
  if (encoding == VoxelEncoding::kInt16 && (voxels + 1) / 2 <= max_texels) {
    return TexelLayout::kPacked;
  }
  return std::nullopt;
}

uint64_t GpuVolume::BufferBytesFor(VoxelEncoding encoding, uint64_t voxels, uint64_t max_texels) {
  const std::optional<TexelLayout> layout = LayoutFor(encoding, voxels, max_texels);
  if (!layout) return 0;
  return TexelsFor(*layout, voxels) * TexelBytes(TexelFormat(encoding, *layout));
}

Result<GpuVolume> GpuVolume::Upload(const gpu::GpuContext& context, const Volume& volume,
                                    const ProgressFn& progress, std::optional<TexelLayout> layout,
                                    const CancelToken& cancel) {
  const uint64_t voxels = static_cast<uint64_t>(volume.geometry().voxel_count());
  const uint64_t max_texels = context.limits().maxTexelBufferElements;
  const bool int16 = volume.encoding() == VoxelEncoding::kInt16;
  if (!int16 && layout == TexelLayout::kPacked) {
    return absl::InvalidArgumentError("GpuVolume: only int16 volumes can be packed");
  }
  if (!layout) layout = LayoutFor(volume.encoding(), voxels, max_texels);
  // The layout's texels; when none fits, the fewest any could take (the message).
  const uint64_t texels =
      layout ? TexelsFor(*layout, voxels)
             : TexelsFor(int16 ? TexelLayout::kPacked : TexelLayout::kPairs, voxels);
  if (!layout || texels > max_texels) {
    return absl::ResourceExhaustedError(
        StrCat("volume of ", DescribeVolumeSize(volume.geometry(), volume.encoding()), " needs ",
               texels, " texels, over this device's texel-buffer limit of ", max_texels, " (",
               int16 ? 2 * max_texels : max_texels, " ", VoxelEncodingName(volume.encoding()),
               " voxels)"));
  }
  const bool pairs = *layout == TexelLayout::kPairs;
  const vk::Format format = TexelFormat(volume.encoding(), *layout);
  const uint64_t texel_bytes = TexelBytes(format);
  const auto features = context.physical_device().getFormatProperties(format).bufferFeatures;
  if (!(features & vk::FormatFeatureFlagBits::eUniformTexelBuffer)) {
    return absl::FailedPreconditionError(StrCat("this device cannot read ", vk::to_string(format),
                                                " texel buffers (a Vulkan mandatory format)"));
  }
  ASSIGN_OR_RETURN(gpu::GpuBuffer buffer,
                   gpu::GpuBuffer::Create(context, texels * texel_bytes,
                                          vk::BufferUsageFlagBits::eUniformTexelBuffer));
  RETURN_IF_ERROR(UploadTexels(buffer, volume.voxels(), pairs, texel_bytes, progress, cancel));
  vk::raii::BufferView view{nullptr};
  RETURN_IF_ERROR(gpu::CatchVulkan("creating the volume's texel view", [&] {
    view = vk::raii::BufferView(
        context.device(),
        vk::BufferViewCreateInfo({}, buffer.handle(), format, 0, texels * texel_bytes));
  }));
  return GpuVolume(std::move(buffer), std::move(view), volume, *layout);
}

Result<const gpu::GpuImage3D*> GpuVolume::Image(const gpu::GpuContext& context,
                                                const Volume& volume) {
  if (image_) return &*image_;
  if (volume.encoding() != encoding_ ||
      volume.geometry().voxel_count() != geometry_.voxel_count()) {
    return absl::InvalidArgumentError("GpuVolume::Image: not the volume that was uploaded");
  }
  if (encoding_ == VoxelEncoding::kFloat32) {
    ASSIGN_OR_RETURN(gpu::GpuImage3D image,
                     gpu::GpuImage3D::Create(context, extent(), vk::Format::eR32Sfloat));
    RETURN_IF_ERROR(image.Upload(volume.voxels().bytes()));
    image_.emplace(std::move(image));
    return &*image_;
  }
  // int16: R16_UNORM of stored + 32768 (flipping the sign bit), a format
  // with linear filtering on lavapipe and desktop GPUs (checked).
  const vk::Format format = vk::Format::eR16Unorm;
  const auto features = context.physical_device().getFormatProperties(format).optimalTilingFeatures;
  if (!(features & vk::FormatFeatureFlagBits::eSampledImageFilterLinear)) {
    return absl::FailedPreconditionError(
        "this device cannot filter R16_UNORM 3D images; use the texel-buffer kernels");
  }
  ASSIGN_OR_RETURN(gpu::GpuImage3D image, gpu::GpuImage3D::Create(context, extent(), format));
  const std::span<const int16_t> stored = volume.voxels().int16s();
  std::vector<uint16_t> shifted(stored.size());
  std::transform(stored.begin(), stored.end(), shifted.begin(), [](int16_t s) {
    return static_cast<uint16_t>(static_cast<uint16_t>(s) ^ 0x8000u);
  });
  RETURN_IF_ERROR(image.Upload(std::as_bytes(std::span<const uint16_t>(shifted))));
  image_.emplace(std::move(image));
  return &*image_;
}

gpu::KernelSpec GpuVolume::Specialize(gpu::KernelSpec spec) const {
  if (spec.specialization.size() < 5) spec.specialization.resize(5, 0);
  spec.specialization[1] = encoding_ == VoxelEncoding::kInt16 ? 1u : 0u;
  spec.specialization[2] = static_cast<uint32_t>(offset_);
  spec.specialization[4] = layout_ == TexelLayout::kPairs ? 1u : 0u;
  return spec;
}

Result<gpu::ComputeKernel> GpuVolume::KernelFor(const gpu::GpuContext& context,
                                                const gpu::ComputeKernel& base) const {
  return gpu::ComputeKernel::Create(context, Specialize(base.spec()));
}

}  // namespace vpm

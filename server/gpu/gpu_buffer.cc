#include "server/gpu/gpu_buffer.h"

#include <cstdint>
#include <cstring>
#include <optional>

#include "server/common/huge_pages.h"

namespace vpm::gpu {

using MemFlag = vk::MemoryPropertyFlagBits;

namespace {

// Host-cached mappings (on a CPU device such as lavapipe, device memory is
// the process's own heap) from this size on (volumes, maps) are advised huge
// pages before their first write (server/common/huge_pages.h): uploading the
// 256^3 float phantom took 400-417 ms, mostly page faults, and takes 20 ms
// (docs/LAVAPIPE.md, "Huge pages"). Smaller ones may share heap pages with
// other allocations, which the advice would cover too.
constexpr vk::DeviceSize kHugeAdviceMinBytes = vk::DeviceSize{8} << 20;

}  // namespace

Result<GpuBuffer> GpuBuffer::Create(const GpuContext& context, vk::DeviceSize size_bytes,
                                    vk::BufferUsageFlags usage) {
  return Allocate(
      context, size_bytes,
      usage | vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst,
      MemFlag::eDeviceLocal, MemFlag::eHostVisible | MemFlag::eHostCoherent);
}

Result<GpuBuffer> GpuBuffer::CreateStaging(const GpuContext& context, vk::DeviceSize size_bytes) {
  return Allocate(context, size_bytes,
                  vk::BufferUsageFlagBits::eTransferSrc | vk::BufferUsageFlagBits::eTransferDst,
                  MemFlag::eHostVisible | MemFlag::eHostCoherent, MemFlag::eHostCached);
}

Result<GpuBuffer> GpuBuffer::Allocate(const GpuContext& context, vk::DeviceSize size_bytes,
                                      vk::BufferUsageFlags usage, vk::MemoryPropertyFlags required,
                                      vk::MemoryPropertyFlags preferred) {
  if (size_bytes == 0) return absl::InvalidArgumentError("GPU buffer of 0 bytes");
  GpuBuffer b;
  b.context_ = &context;
  b.size_bytes_ = size_bytes;
  b.usage_ = usage;
  RETURN_IF_ERROR(CatchVulkan("creating a GPU buffer", [&] {
    b.buffer_ = vk::raii::Buffer(context.device(), vk::BufferCreateInfo({}, size_bytes, usage));
  }));
  const vk::MemoryRequirements req = b.buffer_.getMemoryRequirements();
  ASSIGN_OR_RETURN(const uint32_t type,
                   context.FindMemoryType(req.memoryTypeBits, required, preferred));
  const auto flags = context.memory_flags(type);
  RETURN_IF_ERROR(CatchVulkan("allocating GPU buffer memory", [&] {
    b.memory_ = vk::raii::DeviceMemory(context.device(), vk::MemoryAllocateInfo(req.size, type));
    b.buffer_.bindMemory(*b.memory_, 0);
    if ((flags & MemFlag::eHostVisible) && (flags & MemFlag::eHostCoherent)) {
      b.mapped_ = b.memory_.mapMemory(0, size_bytes);
      b.read_mapped_ = (flags & MemFlag::eHostCached) || !(flags & MemFlag::eDeviceLocal);
      if ((flags & MemFlag::eHostCached) && size_bytes >= kHugeAdviceMinBytes) {
        AdviseHugePages(b.mapped_, size_bytes);
      }
    }
  }));
  return b;
}

Status GpuBuffer::CheckRange(size_t bytes, vk::DeviceSize offset) const {
  if (offset > size_bytes_ || bytes > size_bytes_ - offset) {
    return absl::OutOfRangeError(StrCat("GPU buffer access of ", bytes, " bytes at ", offset,
                                        " exceeds its ", size_bytes_, " bytes"));
  }
  return absl::OkStatus();
}

Status GpuBuffer::Upload(std::span<const std::byte> data, vk::DeviceSize offset_bytes) {
  return Fill(offset_bytes, data.size(), [&](std::span<std::byte> out) {
    std::memcpy(out.data(), data.data(), data.size());
  });
}

Status GpuBuffer::Fill(vk::DeviceSize offset_bytes, size_t size,
                       const std::function<void(std::span<std::byte>)>& fill) {
  RETURN_IF_ERROR(CheckRange(size, offset_bytes));
  if (size == 0) return absl::OkStatus();
  if (mapped_ != nullptr) {
    fill(std::span<std::byte>(static_cast<std::byte*>(mapped_) + offset_bytes, size));
    return absl::OkStatus();
  }
  ASSIGN_OR_RETURN(GpuBuffer staging, CreateStaging(*context_, size));
  fill(std::span<std::byte>(static_cast<std::byte*>(staging.mapped_), size));
  return context_->RunCommands([&](const vk::raii::CommandBuffer& cmd) {
    cmd.copyBuffer(staging.handle(), *buffer_, vk::BufferCopy(0, offset_bytes, size));
  });
}

Status GpuBuffer::Download(std::span<std::byte> out, vk::DeviceSize offset_bytes) const {
  RETURN_IF_ERROR(CheckRange(out.size(), offset_bytes));
  if (out.empty()) return absl::OkStatus();
  if (mapped_ != nullptr && read_mapped_) {
    std::memcpy(out.data(), static_cast<const std::byte*>(mapped_) + offset_bytes, out.size());
    return absl::OkStatus();
  }
  ASSIGN_OR_RETURN(GpuBuffer staging, CreateStaging(*context_, out.size()));
  RETURN_IF_ERROR(context_->RunCommands([&](const vk::raii::CommandBuffer& cmd) {
    cmd.copyBuffer(*buffer_, staging.handle(), vk::BufferCopy(offset_bytes, 0, out.size()));
  }));
  return staging.Download(out);
}

}  // namespace vpm::gpu

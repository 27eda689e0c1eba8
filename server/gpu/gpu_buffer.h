// A Vulkan buffer with its memory, uploads and readbacks.
//
// Memory is device-local; where the device also offers host-visible coherent
// device-local memory (lavapipe, integrated GPUs, resizable BAR) the buffer
// is mapped once and copied directly, otherwise uploads and readbacks go
// through a temporary staging buffer.
#pragma once

#include <cstddef>
#include <functional>
#include <span>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"
#include "server/gpu/gpu_context.h"

namespace vpm::gpu {

class GpuBuffer {
 public:
  // `usage` is extended with transfer source and destination.
  static Result<GpuBuffer> Create(const GpuContext& context, vk::DeviceSize size_bytes,
                                  vk::BufferUsageFlags usage);
  // A buffer in plain host-visible memory (staging), always mapped.
  static Result<GpuBuffer> CreateStaging(const GpuContext& context, vk::DeviceSize size_bytes);

  GpuBuffer(GpuBuffer&&) = default;
  GpuBuffer& operator=(GpuBuffer&&) = default;

  Status Upload(std::span<const std::byte> data, vk::DeviceSize offset_bytes = 0);
  // Writes `size` bytes at `offset_bytes` that `fill` produces in place: it
  // is handed the buffer's own mapping where there is one, else a staging
  // buffer's, copied in after. Saves building the bytes in a vector first
  // (one host copy and its page faults fewer than Upload).
  Status Fill(vk::DeviceSize offset_bytes, size_t size,
              const std::function<void(std::span<std::byte>)>& fill);
  Status Download(std::span<std::byte> out, vk::DeviceSize offset_bytes = 0) const;

  template <typename T>
  Status UploadSpan(std::span<const T> data) {
    return Upload(std::as_bytes(data));
  }
  template <typename T>
  Status DownloadSpan(std::span<T> out) const {
    return Download(std::as_writable_bytes(out));
  }

  vk::Buffer handle() const { return *buffer_; }
  vk::DeviceSize size_bytes() const { return size_bytes_; }
  vk::BufferUsageFlags usage() const { return usage_; }
  bool host_mapped() const { return mapped_ != nullptr; }

 private:
  GpuBuffer() = default;
  static Result<GpuBuffer> Allocate(const GpuContext& context, vk::DeviceSize size_bytes,
                                    vk::BufferUsageFlags usage, vk::MemoryPropertyFlags required,
                                    vk::MemoryPropertyFlags preferred);
  Status CheckRange(size_t bytes, vk::DeviceSize offset) const;

  const GpuContext* context_ = nullptr;
  vk::raii::Buffer buffer_{nullptr};
  vk::raii::DeviceMemory memory_{nullptr};
  void* mapped_ = nullptr;  // non-null when the memory is host-visible and coherent
  // Download reads the mapping itself only where that is fast: host-cached
  // memory (a CPU device, or system RAM), or memory that is not device-local
  // (a staging buffer, the last resort). Device-local memory the host can
  // map (resizable BAR on a discrete GPU) is uncached: reads from it ran at
  // about 30 MB/s on an NVIDIA H200 (docs/benchmarks/GPU_H200.md), so they
  // go through a host-cached staging copy.
  bool read_mapped_ = false;
  vk::DeviceSize size_bytes_ = 0;
  vk::BufferUsageFlags usage_{};
};

}  // namespace vpm::gpu

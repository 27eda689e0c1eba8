// Records a sequence of compute dispatches into one command buffer (the fixed
// cost of a submit is tens of microseconds on lavapipe, so work is batched),
// with a full compute barrier between consecutive dispatches and a timestamp
// pair around each, then submits once and waits.
//
// Every Dispatch checks its invariants against the kernel's spec: argument
// count and kinds, buffer usage, push-constant size, workgroup-count limits.
#pragma once

#include <array>
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"
#include "server/gpu/compute_kernel.h"
#include "server/gpu/gpu_buffer.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/gpu_image3d.h"

namespace vpm::gpu {

// One descriptor: a buffer (storage or uniform), a 3D image (storage image or
// combined image sampler, per the kernel's binding), or a texel-buffer view.
using KernelArg = std::variant<const GpuBuffer*, const GpuImage3D*, vk::BufferView>;

struct DispatchTiming {
  std::string label;
  double gpu_ms = -1.0;  // from timestamps; -1 when the device has none
};

class ComputeBatch {
 public:
  static Result<ComputeBatch> Begin(const GpuContext& context, uint32_t max_dispatches = 64);

  ComputeBatch(ComputeBatch&&) = default;
  ComputeBatch& operator=(ComputeBatch&&) = default;

  Status Dispatch(const ComputeKernel& kernel, std::span<const KernelArg> args,
                  std::span<const std::byte> push_constants, std::array<uint32_t, 3> groups,
                  std::string label = {});

  template <typename Push>
  Status Dispatch(const ComputeKernel& kernel, std::initializer_list<KernelArg> args,
                  const Push& push, std::array<uint32_t, 3> groups, std::string label = {}) {
    return Dispatch(kernel, std::span<const KernelArg>(args.begin(), args.size()),
                    std::as_bytes(std::span<const Push>(&push, 1)), groups, std::move(label));
  }

  // Fills `buffer` with a repeated 32-bit word (e.g. 0 to clear).
  Status Fill(const GpuBuffer& buffer, uint32_t word);

  // Copies every texel of `image` (kept in GENERAL layout) into `buffer`
  // (transfer-destination usage, at least image.size_bytes()), tightly
  // packed, x fastest; timed and counted like a dispatch.
  Status CopyImageToBuffer(const GpuImage3D& image, const GpuBuffer& buffer, std::string label);

  // Copies `regions` of `buffers` (one buffer per region, transfer-source
  // usage) into `image` (kept in GENERAL layout; what lies outside the
  // regions is preserved), after the work recorded before; timed and counted
  // like a dispatch. Recorded here rather than in a submit of its own, it
  // saves a submit and a wait (BackwardMap's update).
  Status CopyBufferToImage(std::span<const std::pair<const GpuBuffer*, vk::BufferImageCopy>> regions,
                           const GpuImage3D& image, std::string label);

  // Submits everything recorded, waits, and returns one timing per dispatch.
  Result<std::vector<DispatchTiming>> SubmitAndWait();

 private:
  ComputeBatch() = default;
  Status CheckArgs(const ComputeKernel& kernel, std::span<const KernelArg> args) const;
  // FailedPrecondition once submitted; ResourceExhausted when max_dispatches
  // timed commands are already recorded.
  Status CheckRoom() const;
  void BarrierIfNeeded();
  // Records a timed copy between `image` and buffers (`what` names it in
  // errors): the image moves from GENERAL to `copy_layout`, `copy` records
  // the copy commands, and the image goes back to GENERAL.
  Status RecordImageCopy(const char* what, const GpuImage3D& image, vk::ImageLayout copy_layout,
                         std::string label, const std::function<void()>& copy);

  const GpuContext* context_ = nullptr;
  uint32_t max_dispatches_ = 0;
  vk::raii::DescriptorPool descriptor_pool_{nullptr};
  vk::raii::QueryPool query_pool_{nullptr};
  // From the recording thread's pool (GpuContext::ThreadCommandPool): a batch
  // is recorded, submitted and destroyed on one thread.
  std::optional<vk::raii::CommandBuffer> commands_;
  std::vector<vk::raii::DescriptorSet> sets_;
  std::vector<std::string> labels_;
  bool needs_barrier_ = false;
  bool submitted_ = false;
};

}  // namespace vpm::gpu

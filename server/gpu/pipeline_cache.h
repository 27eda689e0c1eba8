// The compute pipelines of one GpuContext, built once per kernel spec and
// shared by every ComputeKernel made from it. Pipeline creation costs 1-3 ms
// on lavapipe (a JIT compile), and lavapipe keeps the machine code of a
// destroyed pipeline mapped, so a server that built pipelines per session
// grew by about 2 MB per session (bench/soak.sh); with the cache a process
// holds one pipeline per distinct kernel.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <tuple>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"

namespace vpm::gpu {

struct KernelSpec;

// What a compute pipeline is made of; destroyed with the cache.
struct PipelineObjects {
  vk::raii::DescriptorSetLayout set_layout{nullptr};
  vk::raii::PipelineLayout layout{nullptr};
  vk::raii::ShaderModule module{nullptr};
  vk::raii::Pipeline pipeline{nullptr};
};

class PipelineCache {
 public:
  // The pipeline of `spec` (already validated against the device's limits),
  // built on first use. Thread-safe. Specs are the same kernel when their
  // SPIR-V (by address: the embedded arrays), bindings, push-constant size,
  // local size and specialization constants are equal.
  Result<std::shared_ptr<const PipelineObjects>> Get(const vk::raii::Device& device,
                                                     const KernelSpec& spec);
  size_t size() const;

 private:
  using Key = std::tuple<const uint32_t*, size_t, std::vector<int>, uint32_t,
                         std::array<uint32_t, 3>, std::vector<uint32_t>>;
  mutable std::mutex mutex_;
  std::map<Key, std::shared_ptr<const PipelineObjects>> pipelines_;
};

}  // namespace vpm::gpu

// A compute pipeline built from embedded SPIR-V, with its descriptor-set
// layout (one set, binding i of type bindings[i]) and push-constant range.
// The Vulkan objects come from the context's PipelineCache: kernels of the
// same spec share one pipeline.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/gpu/pipeline_cache.h"

namespace vpm::gpu {

struct KernelSpec {
  std::string name;                             // for messages and timings
  std::span<const uint32_t> spirv;              // the embedded k<Name>Spv array
  std::vector<vk::DescriptorType> bindings;     // set 0, binding i
  uint32_t push_constant_bytes = 0;             // sizeof the mirrored push struct
  std::array<uint32_t, 3> local_size{1, 1, 1};  // must equal the shader's local_size
  // 32-bit specialization constants: constant_id i takes specialization[i]
  // (a shader's defaults apply to ids past the end).
  std::vector<uint32_t> specialization;
};

class ComputeKernel {
 public:
  static Result<ComputeKernel> Create(const GpuContext& context, KernelSpec spec);

  ComputeKernel(ComputeKernel&&) = default;
  ComputeKernel& operator=(ComputeKernel&&) = default;

  const KernelSpec& spec() const { return spec_; }
  vk::Pipeline pipeline() const { return *objects_->pipeline; }
  vk::PipelineLayout layout() const { return *objects_->layout; }
  vk::DescriptorSetLayout set_layout() const { return *objects_->set_layout; }

  // Workgroups needed to cover `threads` invocations (ceil division per axis).
  std::array<uint32_t, 3> GroupsFor(std::array<uint32_t, 3> threads) const;

 private:
  ComputeKernel() = default;

  KernelSpec spec_;
  // Shared with every kernel of the same spec (GpuContext::pipelines()).
  std::shared_ptr<const PipelineObjects> objects_;
};

}  // namespace vpm::gpu

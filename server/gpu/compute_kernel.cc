#include "server/gpu/compute_kernel.h"

namespace vpm::gpu {

Result<ComputeKernel> ComputeKernel::Create(const GpuContext& context, KernelSpec spec) {
  if (spec.spirv.empty() || spec.spirv[0] != 0x07230203u) {
    return absl::InvalidArgumentError(
        absl::StrCat("kernel ", spec.name, ": SPIR-V is empty or lacks the magic number"));
  }
  const auto& limits = context.limits();
  const uint64_t invocations =
      uint64_t{spec.local_size[0]} * spec.local_size[1] * spec.local_size[2];
  for (int a = 0; a < 3; ++a) {
    if (spec.local_size[a] == 0 || spec.local_size[a] > limits.maxComputeWorkGroupSize[a]) {
      return absl::InvalidArgumentError(absl::StrCat("kernel ", spec.name, ": local size ",
                                                     spec.local_size[a], " on axis ", a,
                                                     " exceeds the device limit"));
    }
  }
  if (invocations > limits.maxComputeWorkGroupInvocations) {
    return absl::InvalidArgumentError(
        absl::StrCat("kernel ", spec.name, ": ", invocations, " invocations per workgroup"));
  }
  if (spec.push_constant_bytes > limits.maxPushConstantsSize || spec.push_constant_bytes % 4 != 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "kernel ", spec.name, ": push constants of ", spec.push_constant_bytes,
        " bytes (must be a multiple of 4, at most ", limits.maxPushConstantsSize, ")"));
  }
  ComputeKernel k;
  RETURN_IF_ERROR(CatchVulkan("creating a compute pipeline", [&] {
    std::vector<vk::DescriptorSetLayoutBinding> bindings;
    for (uint32_t i = 0; i < spec.bindings.size(); ++i) {
      bindings.emplace_back(i, spec.bindings[i], 1, vk::ShaderStageFlagBits::eCompute);
    }
    k.set_layout_ = vk::raii::DescriptorSetLayout(context.device(), {{}, bindings});
    vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, spec.push_constant_bytes);
    vk::DescriptorSetLayout set_layout = *k.set_layout_;
    vk::PipelineLayoutCreateInfo layout_info({}, set_layout);
    if (spec.push_constant_bytes > 0) layout_info.setPushConstantRanges(range);
    k.layout_ = vk::raii::PipelineLayout(context.device(), layout_info);
    k.module_ = vk::raii::ShaderModule(
        context.device(),
        vk::ShaderModuleCreateInfo({}, spec.spirv.size_bytes(), spec.spirv.data()));
    std::vector<vk::SpecializationMapEntry> entries;
    for (uint32_t i = 0; i < spec.specialization.size(); ++i) {
      entries.emplace_back(i, i * uint32_t(sizeof(uint32_t)), sizeof(uint32_t));
    }
    const vk::SpecializationInfo specialization(uint32_t(entries.size()), entries.data(),
                                                spec.specialization.size() * sizeof(uint32_t),
                                                spec.specialization.data());
    vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *k.module_,
                                            "main", entries.empty() ? nullptr : &specialization);
    k.pipeline_ = vk::raii::Pipeline(context.device(), nullptr,
                                     vk::ComputePipelineCreateInfo({}, stage, *k.layout_));
  }));
  k.spec_ = std::move(spec);
  return k;
}

std::array<uint32_t, 3> ComputeKernel::GroupsFor(std::array<uint32_t, 3> threads) const {
  std::array<uint32_t, 3> groups{};
  for (int a = 0; a < 3; ++a) {
    groups[a] = (threads[a] + spec_.local_size[a] - 1) / spec_.local_size[a];
  }
  return groups;
}

}  // namespace vpm::gpu

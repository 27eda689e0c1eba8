#include "server/gpu/pipeline_cache.h"

#include "server/gpu/compute_kernel.h"

namespace vpm::gpu {

Result<std::shared_ptr<const PipelineObjects>> PipelineCache::Get(const vk::raii::Device& device,
                                                                  const KernelSpec& spec) {
  std::vector<int> bindings;
  for (vk::DescriptorType type : spec.bindings) bindings.push_back(int(type));
  Key key{spec.spirv.data(),        spec.spirv.size(), bindings,
          spec.push_constant_bytes, spec.local_size,   spec.specialization};
  // Held while building: a second thread asking for the same kernel waits
  // rather than compiling it twice.
  std::lock_guard lock(mutex_);
  if (auto found = pipelines_.find(key); found != pipelines_.end()) return found->second;
  auto objects = std::make_shared<PipelineObjects>();
  RETURN_IF_ERROR(CatchVulkan("creating a compute pipeline", [&] {
    std::vector<vk::DescriptorSetLayoutBinding> layout_bindings;
    for (uint32_t i = 0; i < spec.bindings.size(); ++i) {
      layout_bindings.emplace_back(i, spec.bindings[i], 1, vk::ShaderStageFlagBits::eCompute);
    }
    objects->set_layout = vk::raii::DescriptorSetLayout(device, {{}, layout_bindings});
    vk::PushConstantRange range(vk::ShaderStageFlagBits::eCompute, 0, spec.push_constant_bytes);
    vk::DescriptorSetLayout set_layout = *objects->set_layout;
    vk::PipelineLayoutCreateInfo layout_info({}, set_layout);
    if (spec.push_constant_bytes > 0) layout_info.setPushConstantRanges(range);
    objects->layout = vk::raii::PipelineLayout(device, layout_info);
    objects->module = vk::raii::ShaderModule(
        device, vk::ShaderModuleCreateInfo({}, spec.spirv.size_bytes(), spec.spirv.data()));
    std::vector<vk::SpecializationMapEntry> entries;
    for (uint32_t i = 0; i < spec.specialization.size(); ++i) {
      entries.emplace_back(i, i * uint32_t(sizeof(uint32_t)), sizeof(uint32_t));
    }
    const vk::SpecializationInfo specialization(uint32_t(entries.size()), entries.data(),
                                                spec.specialization.size() * sizeof(uint32_t),
                                                spec.specialization.data());
    vk::PipelineShaderStageCreateInfo stage({}, vk::ShaderStageFlagBits::eCompute, *objects->module,
                                            "main", entries.empty() ? nullptr : &specialization);
    objects->pipeline = vk::raii::Pipeline(
        device, nullptr, vk::ComputePipelineCreateInfo({}, stage, *objects->layout));
  }));
  return pipelines_.emplace(std::move(key), std::move(objects)).first->second;
}

size_t PipelineCache::size() const {
  std::lock_guard lock(mutex_);
  return pipelines_.size();
}

}  // namespace vpm::gpu

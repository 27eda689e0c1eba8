#include "server/gpu/compute_kernel.h"

#include "server/gpu/pipeline_cache.h"

namespace vpm::gpu {

Result<ComputeKernel> ComputeKernel::Create(const GpuContext& context, KernelSpec spec) {
  if (spec.spirv.empty() || spec.spirv[0] != 0x07230203u) {
    return absl::InvalidArgumentError(
        StrCat("kernel ", spec.name, ": SPIR-V is empty or lacks the magic number"));
  }
  const auto& limits = context.limits();
  const uint64_t invocations =
      uint64_t{spec.local_size[0]} * spec.local_size[1] * spec.local_size[2];
  for (int a = 0; a < 3; ++a) {
    if (spec.local_size[a] == 0 || spec.local_size[a] > limits.maxComputeWorkGroupSize[a]) {
      return absl::InvalidArgumentError(StrCat("kernel ", spec.name, ": local size ",
                                                     spec.local_size[a], " on axis ", a,
                                                     " exceeds the device limit"));
    }
  }
  if (invocations > limits.maxComputeWorkGroupInvocations) {
    return absl::InvalidArgumentError(
        StrCat("kernel ", spec.name, ": ", invocations, " invocations per workgroup"));
  }
  if (spec.push_constant_bytes > limits.maxPushConstantsSize || spec.push_constant_bytes % 4 != 0) {
    return absl::InvalidArgumentError(StrCat(
        "kernel ", spec.name, ": push constants of ", spec.push_constant_bytes,
        " bytes (must be a multiple of 4, at most ", limits.maxPushConstantsSize, ")"));
  }
  ComputeKernel k;
  ASSIGN_OR_RETURN(k.objects_, context.pipelines().Get(context.device(), spec));
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

#include "server/gpu/compute_batch.h"

namespace vpm::gpu {
namespace {

using DT = vk::DescriptorType;

bool IsBufferType(DT t) { return t == DT::eStorageBuffer || t == DT::eUniformBuffer; }
bool IsImageType(DT t) { return t == DT::eStorageImage || t == DT::eCombinedImageSampler; }
bool IsTexelType(DT t) { return t == DT::eUniformTexelBuffer || t == DT::eStorageTexelBuffer; }

const vk::MemoryBarrier kComputeToCompute(vk::AccessFlagBits::eShaderWrite |
                                              vk::AccessFlagBits::eTransferWrite,
                                          vk::AccessFlagBits::eShaderRead |
                                              vk::AccessFlagBits::eShaderWrite |
                                              vk::AccessFlagBits::eTransferRead |
                                              vk::AccessFlagBits::eTransferWrite);

// The image's layout from `from` to `to` around a copy, ordered after and
// before compute and transfer work.
void ImageLayoutBarrier(const vk::raii::CommandBuffer& cmd, vk::Image image, vk::ImageLayout from,
                        vk::ImageLayout to) {
  const auto all = vk::AccessFlagBits::eMemoryRead | vk::AccessFlagBits::eMemoryWrite;
  const vk::ImageMemoryBarrier barrier(
      all, all, from, to, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED, image,
      vk::ImageSubresourceRange(vk::ImageAspectFlagBits::eColor, 0, 1, 0, 1));
  const auto stages =
      vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer;
  cmd.pipelineBarrier(stages, stages, {}, {}, {}, barrier);
}

}  // namespace

Result<ComputeBatch> ComputeBatch::Begin(const GpuContext& context, uint32_t max_dispatches) {
  ComputeBatch b;
  b.context_ = &context;
  b.max_dispatches_ = max_dispatches;
  RETURN_IF_ERROR(CatchVulkan("starting a compute batch", [&] {
    // Up to 16 descriptors of each kind per dispatch.
    const uint32_t n = 16 * max_dispatches;
    const std::array<vk::DescriptorPoolSize, 6> sizes{{{DT::eStorageBuffer, n},
                                                       {DT::eUniformBuffer, n},
                                                       {DT::eStorageImage, n},
                                                       {DT::eCombinedImageSampler, n},
                                                       {DT::eUniformTexelBuffer, n},
                                                       {DT::eStorageTexelBuffer, n}}};
    b.descriptor_pool_ = vk::raii::DescriptorPool(
        context.device(),
        {vk::DescriptorPoolCreateFlagBits::eFreeDescriptorSet, max_dispatches, sizes});
    if (context.timestamp_period_ns() > 0) {
      b.query_pool_ = vk::raii::QueryPool(context.device(),
                                          {{}, vk::QueryType::eTimestamp, 2 * max_dispatches});
    }
    b.commands_.emplace(context.AllocateCommandBuffer());
    b.commands_->begin({vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
    if (*b.query_pool_) b.commands_->resetQueryPool(*b.query_pool_, 0, 2 * max_dispatches);
  }));
  return b;
}

Status ComputeBatch::CheckArgs(const ComputeKernel& kernel, std::span<const KernelArg> args) const {
  const KernelSpec& spec = kernel.spec();
  if (args.size() != spec.bindings.size()) {
    return absl::InvalidArgumentError(StrCat(
        "kernel ", spec.name, " takes ", spec.bindings.size(), " bindings, got ", args.size()));
  }
  for (size_t i = 0; i < args.size(); ++i) {
    const DT type = spec.bindings[i];
    bool ok = false;
    if (const auto* buffer = std::get_if<const GpuBuffer*>(&args[i])) {
      const auto need = type == DT::eStorageBuffer ? vk::BufferUsageFlagBits::eStorageBuffer
                                                   : vk::BufferUsageFlagBits::eUniformBuffer;
      ok = *buffer != nullptr && IsBufferType(type) && static_cast<bool>((*buffer)->usage() & need);
    } else if (const auto* image = std::get_if<const GpuImage3D*>(&args[i])) {
      ok = *image != nullptr && IsImageType(type);
    } else {
      ok = static_cast<bool>(std::get<vk::BufferView>(args[i])) && IsTexelType(type);
    }
    if (!ok) {
      return absl::InvalidArgumentError(
          StrCat("kernel ", spec.name, ": binding ", i, " must be a ", vk::to_string(type)));
    }
  }
  return absl::OkStatus();
}

void ComputeBatch::BarrierIfNeeded() {
  if (needs_barrier_) {
    commands_->pipelineBarrier(
        vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
        vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer, {},
        kComputeToCompute, {}, {});
  }
  needs_barrier_ = true;
}

Status ComputeBatch::Dispatch(const ComputeKernel& kernel, std::span<const KernelArg> args,
                              std::span<const std::byte> push_constants,
                              std::array<uint32_t, 3> groups, std::string label) {
  const KernelSpec& spec = kernel.spec();
  RETURN_IF_ERROR(CheckRoom());
  RETURN_IF_ERROR(CheckArgs(kernel, args));
  if (push_constants.size() != spec.push_constant_bytes) {
    return absl::InvalidArgumentError(StrCat("kernel ", spec.name, ": push constants of ",
                                                   push_constants.size(), " bytes, expected ",
                                                   spec.push_constant_bytes));
  }
  const auto& max_groups = context_->limits().maxComputeWorkGroupCount;
  for (int a = 0; a < 3; ++a) {
    if (groups[a] == 0 || groups[a] > max_groups[a]) {
      return absl::InvalidArgumentError(StrCat("kernel ", spec.name, ": ", groups[a],
                                                     " workgroups on axis ", a, " (limit ",
                                                     max_groups[a], ")"));
    }
  }
  return CatchVulkan("recording a dispatch", [&] {
    vk::DescriptorSetLayout set_layout = kernel.set_layout();
    vk::raii::DescriptorSets sets(context_->device(), {*descriptor_pool_, set_layout});
    vk::raii::DescriptorSet set = std::move(sets.front());
    std::vector<vk::DescriptorBufferInfo> buffer_infos(args.size());
    std::vector<vk::DescriptorImageInfo> image_infos(args.size());
    std::vector<vk::BufferView> texel_views(args.size());
    std::vector<vk::WriteDescriptorSet> writes;
    for (uint32_t i = 0; i < args.size(); ++i) {
      vk::WriteDescriptorSet w(*set, i, 0, 1, spec.bindings[i]);
      if (const auto* buffer = std::get_if<const GpuBuffer*>(&args[i])) {
        buffer_infos[i] = vk::DescriptorBufferInfo((*buffer)->handle(), 0, VK_WHOLE_SIZE);
        w.setPBufferInfo(&buffer_infos[i]);
      } else if (const auto* image = std::get_if<const GpuImage3D*>(&args[i])) {
        image_infos[i] = vk::DescriptorImageInfo((*image)->linear_sampler(), (*image)->view(),
                                                 vk::ImageLayout::eGeneral);
        w.setPImageInfo(&image_infos[i]);
      } else {
        texel_views[i] = std::get<vk::BufferView>(args[i]);
        w.setPTexelBufferView(&texel_views[i]);
      }
      writes.push_back(w);
    }
    context_->device().updateDescriptorSets(writes, {});
    BarrierIfNeeded();
    const uint32_t q = static_cast<uint32_t>(labels_.size());
    if (*query_pool_) {
      commands_->writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *query_pool_, 2 * q);
    }
    commands_->bindPipeline(vk::PipelineBindPoint::eCompute, kernel.pipeline());
    commands_->bindDescriptorSets(vk::PipelineBindPoint::eCompute, kernel.layout(), 0, *set, {});
    if (!push_constants.empty()) {
      commands_->pushConstants<std::byte>(kernel.layout(), vk::ShaderStageFlagBits::eCompute, 0,
                                          push_constants);
    }
    commands_->dispatch(groups[0], groups[1], groups[2]);
    if (*query_pool_) {
      commands_->writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *query_pool_, 2 * q + 1);
    }
    sets_.push_back(std::move(set));
    labels_.push_back(label.empty() ? spec.name : std::move(label));
  });
}

Status ComputeBatch::Fill(const GpuBuffer& buffer, uint32_t word) {
  if (submitted_) return absl::FailedPreconditionError("compute batch already submitted");
  return CatchVulkan("recording a buffer fill", [&] {
    BarrierIfNeeded();
    commands_->fillBuffer(buffer.handle(), 0, VK_WHOLE_SIZE, word);
  });
}

Status ComputeBatch::CheckRoom() const {
  if (submitted_) return absl::FailedPreconditionError("compute batch already submitted");
  if (labels_.size() >= max_dispatches_) {
    return absl::ResourceExhaustedError(
        StrCat("compute batch holds at most ", max_dispatches_, " dispatches"));
  }
  return absl::OkStatus();
}

Status ComputeBatch::RecordImageCopy(const char* what, const GpuImage3D& image,
                                     vk::ImageLayout copy_layout, std::string label,
                                     const std::function<void()>& copy) {
  return CatchVulkan(what, [&] {
    BarrierIfNeeded();
    const uint32_t q = static_cast<uint32_t>(labels_.size());
    if (*query_pool_) {
      commands_->writeTimestamp(vk::PipelineStageFlagBits::eTopOfPipe, *query_pool_, 2 * q);
    }
    ImageLayoutBarrier(*commands_, image.image(), vk::ImageLayout::eGeneral, copy_layout);
    copy();
    ImageLayoutBarrier(*commands_, image.image(), copy_layout, vk::ImageLayout::eGeneral);
    if (*query_pool_) {
      commands_->writeTimestamp(vk::PipelineStageFlagBits::eBottomOfPipe, *query_pool_, 2 * q + 1);
    }
    labels_.push_back(std::move(label));
  });
}

Status ComputeBatch::CopyImageToBuffer(const GpuImage3D& image, const GpuBuffer& buffer,
                                       std::string label) {
  RETURN_IF_ERROR(CheckRoom());
  if (!(buffer.usage() & vk::BufferUsageFlagBits::eTransferDst) ||
      buffer.size_bytes() < image.size_bytes()) {
    return absl::InvalidArgumentError(StrCat(
        "copying a 3D image of ", image.size_bytes(), " bytes needs a transfer-destination ",
        "buffer at least as large; got ", buffer.size_bytes(), " bytes"));
  }
  // The image lives in GENERAL; the copy reads it in TRANSFER_SRC_OPTIMAL
  // (what the validation layer asks for, and what a GPU may copy fastest).
  constexpr auto kSrc = vk::ImageLayout::eTransferSrcOptimal;
  return RecordImageCopy("recording an image-to-buffer copy", image, kSrc, std::move(label), [&] {
    const auto& e = image.extent();
    const vk::BufferImageCopy region(0, 0, 0, {vk::ImageAspectFlagBits::eColor, 0, 0, 1},
                                     {0, 0, 0}, vk::Extent3D(e[0], e[1], e[2]));
    commands_->copyImageToBuffer(image.image(), kSrc, buffer.handle(), region);
  });
}

Status ComputeBatch::CopyBufferToImage(
    std::span<const std::pair<const GpuBuffer*, vk::BufferImageCopy>> regions,
    const GpuImage3D& image, std::string label) {
  RETURN_IF_ERROR(CheckRoom());
  for (const auto& [buffer, region] : regions) {
    if (!(buffer->usage() & vk::BufferUsageFlagBits::eTransferSrc)) {
      return absl::InvalidArgumentError("copying a buffer into an image needs transfer-source usage");
    }
  }
  // The copy writes the image in TRANSFER_DST_OPTIMAL.
  constexpr auto kDst = vk::ImageLayout::eTransferDstOptimal;
  return RecordImageCopy("recording a buffer-to-image copy", image, kDst, std::move(label), [&] {
    for (const auto& [buffer, region] : regions) {
      commands_->copyBufferToImage(buffer->handle(), image.image(), kDst, region);
    }
  });
}

Result<std::vector<DispatchTiming>> ComputeBatch::SubmitAndWait() {
  if (submitted_) return absl::FailedPreconditionError("compute batch already submitted");
  submitted_ = true;
  RETURN_IF_ERROR(CatchVulkan("ending a compute batch", [&] {
    // Make every shader write visible to the host (mapped readbacks) and to
    // later transfers.
    vk::MemoryBarrier to_host(vk::AccessFlagBits::eShaderWrite | vk::AccessFlagBits::eTransferWrite,
                              vk::AccessFlagBits::eHostRead | vk::AccessFlagBits::eTransferRead);
    commands_->pipelineBarrier(
        vk::PipelineStageFlagBits::eComputeShader | vk::PipelineStageFlagBits::eTransfer,
        vk::PipelineStageFlagBits::eHost | vk::PipelineStageFlagBits::eTransfer, {}, to_host, {},
        {});
    commands_->end();
  }));
  RETURN_IF_ERROR(context_->SubmitAndWait(*commands_));
  std::vector<DispatchTiming> timings;
  for (const auto& label : labels_) timings.push_back({label, -1.0});
  if (*query_pool_ && !labels_.empty()) {
    RETURN_IF_ERROR(CatchVulkan("reading GPU timestamps", [&] {
      const uint32_t count = 2 * static_cast<uint32_t>(labels_.size());
      auto [result, ticks] = query_pool_.getResults<uint64_t>(
          0, count, count * sizeof(uint64_t), sizeof(uint64_t),
          vk::QueryResultFlagBits::e64 | vk::QueryResultFlagBits::eWait);
      const double ms_per_tick = context_->timestamp_period_ns() * 1e-6;
      for (size_t d = 0; d < labels_.size(); ++d) {
        timings[d].gpu_ms = static_cast<double>(ticks[2 * d + 1] - ticks[2 * d]) * ms_per_tick;
      }
    }));
  }
  return timings;
}

}  // namespace vpm::gpu

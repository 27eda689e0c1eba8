// The Vulkan instance, the chosen physical device, a logical device with one
// compute queue, and the validation-layer message log.
//
// Device choice: VPM_VULKAN_DEVICE (or Options::device_selector) forces one,
// by index ("1") or by a case-insensitive substring of its name ("llvmpipe");
// otherwise a discrete GPU, then an integrated one, then a virtual one, then a
// CPU implementation (lavapipe). The choice is logged to stderr.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <vulkan/vulkan_raii.hpp>

#include "server/common/status.h"

namespace vpm::gpu {

class PipelineCache;

class GpuContext {
 public:
  struct Options {
    std::string device_selector;      // "" = automatic (env VPM_VULKAN_DEVICE overrides)
    bool enable_validation = false;   // also on with env VPM_VULKAN_VALIDATION=1
    bool require_validation = false;  // fail if the Khronos layer is not installed
    bool log_device = true;           // print the chosen device on stderr
  };

  static Result<std::unique_ptr<GpuContext>> Create(const Options& options);
  ~GpuContext();
  GpuContext(const GpuContext&) = delete;
  GpuContext& operator=(const GpuContext&) = delete;

  const vk::raii::Device& device() const { return device_; }
  const vk::raii::PhysicalDevice& physical_device() const { return physical_device_; }
  const vk::raii::Queue& queue() const { return queue_; }
  uint32_t queue_family() const { return queue_family_; }
  const vk::PhysicalDeviceLimits& limits() const { return properties_.limits; }
  const std::string& device_name() const { return device_name_; }
  bool is_cpu_device() const { return properties_.deviceType == vk::PhysicalDeviceType::eCpu; }
  bool is_discrete_gpu() const {
    return properties_.deviceType == vk::PhysicalDeviceType::eDiscreteGpu;
  }

  // Nanoseconds per timestamp tick; 0 when the queue cannot write timestamps.
  double timestamp_period_ns() const { return timestamp_period_ns_; }

  // A memory type index with all of `required` (and, when possible, all of
  // `preferred`) among those allowed by `type_bits`.
  Result<uint32_t> FindMemoryType(uint32_t type_bits, vk::MemoryPropertyFlags required,
                                  vk::MemoryPropertyFlags preferred) const;
  vk::MemoryPropertyFlags memory_flags(uint32_t type_index) const;

  // Submits one recorded command buffer and waits for it. The queue is shared
  // by every user of the context, so submission is serialised here.
  Status SubmitAndWait(const vk::raii::CommandBuffer& commands) const;
  // The calling thread's command pool (made on its first use). Command pools
  // are externally synchronised, recording into their buffers included, so
  // one pool shared by the render threads let two recordings corrupt each
  // other (a lavapipe crash under load, bench/soak.sh); a pool per recording
  // instead made lavapipe compile code per pool. A buffer from it must be
  // recorded and freed on the same thread.
  const vk::raii::CommandPool& ThreadCommandPool() const;
  // One primary command buffer from the calling thread's pool.
  vk::raii::CommandBuffer AllocateCommandBuffer() const;
  // Records `record` into a fresh command buffer, submits it and waits: for
  // one-off transfers (uploads, readbacks, layout changes).
  Status RunCommands(const std::function<void(const vk::raii::CommandBuffer&)>& record) const;

  // The compute pipelines built on this device (ComputeKernel::Create).
  PipelineCache& pipelines() const { return *pipelines_; }

  bool validation_enabled() const { return validation_enabled_; }
  // Validation messages of severity warning or error seen so far.
  std::vector<std::string> validation_messages() const;
  void ClearValidationMessages();
  void RecordValidationMessage(std::string message);
  // Validation messages seen by every context of this process, including
  // those reported while a context was being destroyed.
  static uint64_t process_validation_message_count();

 private:
  GpuContext() = default;
  Status Init(const Options& options);
  Status PickPhysicalDevice(const std::string& selector);

  // The message log outlives every Vulkan object (declared first), since the
  // layer reports leaks while the device is destroyed.
  mutable std::mutex messages_mutex_;
  std::vector<std::string> messages_;

  // Declared in dependency order: destroyed in reverse.
  vk::raii::Context context_;
  vk::raii::Instance instance_{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
  vk::raii::PhysicalDevice physical_device_{nullptr};
  vk::raii::Device device_{nullptr};
  vk::raii::Queue queue_{nullptr};
  std::unique_ptr<PipelineCache> pipelines_;  // destroyed before the device
  mutable std::mutex pools_mutex_;            // guards the map, not the pools
  mutable std::map<std::thread::id, std::unique_ptr<vk::raii::CommandPool>> thread_pools_;
  mutable std::mutex queue_mutex_;  // so is the queue

  uint32_t queue_family_ = 0;
  vk::PhysicalDeviceProperties properties_{};
  vk::PhysicalDeviceMemoryProperties memory_properties_{};
  std::string device_name_;
  double timestamp_period_ns_ = 0.0;
  bool validation_enabled_ = false;
};

// Runs `fn` and turns a vk::SystemError (or std::exception) into a Status;
// Vulkan-Hpp RAII reports failure by exceptions, vpm by values.
template <typename Fn>
Status CatchVulkan(const char* what, Fn&& fn) {
  try {
    fn();
    return absl::OkStatus();
  } catch (const vk::OutOfDeviceMemoryError& e) {
    return absl::ResourceExhaustedError(StrCat(what, ": out of device memory: ", e.what()));
  } catch (const vk::OutOfHostMemoryError& e) {
    return absl::ResourceExhaustedError(StrCat(what, ": out of host memory: ", e.what()));
  } catch (const std::exception& e) {
    return absl::InternalError(StrCat(what, ": ", e.what()));
  }
}

}  // namespace vpm::gpu

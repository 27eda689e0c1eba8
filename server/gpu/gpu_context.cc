#include "server/gpu/gpu_context.h"

#include "server/gpu/pipeline_cache.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <iostream>
#include <optional>

namespace vpm::gpu {
namespace {

std::atomic<uint64_t> g_validation_messages{0};

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

VKAPI_ATTR VkBool32 VKAPI_CALL OnValidationMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                   VkDebugUtilsMessageTypeFlagsEXT /*types*/,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                   void* user) {
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    auto* context = static_cast<GpuContext*>(user);
    std::string message = data->pMessage ? data->pMessage : "(no message)";
    std::cerr << "[vulkan validation] " << message << "\n";
    context->RecordValidationMessage(std::move(message));
  }
  return VK_FALSE;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

int DeviceTypeRank(vk::PhysicalDeviceType type) {
  switch (type) {
    case vk::PhysicalDeviceType::eDiscreteGpu:
      return 0;
    case vk::PhysicalDeviceType::eIntegratedGpu:
      return 1;
    case vk::PhysicalDeviceType::eVirtualGpu:
      return 2;
    case vk::PhysicalDeviceType::eCpu:
      return 3;
    default:
      return 4;
  }
}

bool EnvFlag(const char* name) {
  const char* v = std::getenv(name);
  return v != nullptr && v[0] != '\0' && std::string(v) != "0";
}

std::optional<uint32_t> ComputeQueueFamily(const vk::raii::PhysicalDevice& device) {
  const auto families = device.getQueueFamilyProperties();
  for (uint32_t i = 0; i < families.size(); ++i) {
    if (families[i].queueFlags & vk::QueueFlagBits::eCompute) return i;
  }
  return std::nullopt;
}

}  // namespace

Result<std::unique_ptr<GpuContext>> GpuContext::Create(const Options& options) {
  std::unique_ptr<GpuContext> context(new GpuContext());
  RETURN_IF_ERROR(context->Init(options));
  return context;
}

GpuContext::~GpuContext() {
  if (*device_) device_.waitIdle();
  pipelines_.reset();  // before the device (also by declaration order)
}

Status GpuContext::Init(const Options& options) {
  bool want_validation = options.enable_validation || EnvFlag("VPM_VULKAN_VALIDATION");
  std::string selector = options.device_selector;
  if (const char* env = std::getenv("VPM_VULKAN_DEVICE"); env != nullptr && selector.empty()) {
    selector = env;
  }
  Status status = CatchVulkan("creating the Vulkan instance", [&] {
    const auto layers = context_.enumerateInstanceLayerProperties();
    const bool layer_present = std::any_of(layers.begin(), layers.end(), [](const auto& l) {
      return std::string(l.layerName.data()) == kValidationLayer;
    });
    validation_enabled_ = want_validation && layer_present;
    if (want_validation && !layer_present && options.require_validation) {
      throw std::runtime_error("the Khronos validation layer is not installed");
    }
    vk::ApplicationInfo app("vpm", 1, "vpm", 1, VK_API_VERSION_1_1);
    std::vector<const char*> enabled_layers;
    std::vector<const char*> extensions;
    if (validation_enabled_) {
      enabled_layers.push_back(kValidationLayer);
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    vk::InstanceCreateInfo info({}, &app, enabled_layers, extensions);
    instance_ = vk::raii::Instance(context_, info);
    if (validation_enabled_) {
      using Severity = vk::DebugUtilsMessageSeverityFlagBitsEXT;
      using Type = vk::DebugUtilsMessageTypeFlagBitsEXT;
      vk::DebugUtilsMessengerCreateInfoEXT messenger_info(
          {}, Severity::eWarning | Severity::eError,
          Type::eGeneral | Type::eValidation | Type::ePerformance, &OnValidationMessage, this);
      messenger_ = vk::raii::DebugUtilsMessengerEXT(instance_, messenger_info);
    }
  });
  RETURN_IF_ERROR(status);
  RETURN_IF_ERROR(PickPhysicalDevice(selector));
  return CatchVulkan("creating the Vulkan device", [&] {
    const float priority = 1.0f;
    vk::DeviceQueueCreateInfo queue_info({}, queue_family_, 1, &priority);
    vk::DeviceCreateInfo device_info({}, queue_info);
    device_ = vk::raii::Device(physical_device_, device_info);
    queue_ = vk::raii::Queue(device_, queue_family_, 0);
    pipelines_ = std::make_unique<PipelineCache>();
    if (options.log_device) {
      std::cerr << "vpm: Vulkan device '" << device_name_ << "' ("
                << vk::to_string(properties_.deviceType) << ", API "
                << VK_API_VERSION_MAJOR(properties_.apiVersion) << "."
                << VK_API_VERSION_MINOR(properties_.apiVersion) << ")"
                << (validation_enabled_ ? ", validation on" : "") << "\n";
    }
  });
}

Status GpuContext::PickPhysicalDevice(const std::string& selector) {
  std::vector<vk::raii::PhysicalDevice> devices;
  RETURN_IF_ERROR(CatchVulkan("enumerating Vulkan devices",
                              [&] { devices = instance_.enumeratePhysicalDevices(); }));
  std::vector<size_t> usable;
  std::string names;
  for (size_t i = 0; i < devices.size(); ++i) {
    const auto props = devices[i].getProperties();
    StrAppend(&names, names.empty() ? "" : ", ", i, ": ", props.deviceName.data());
    if (props.apiVersion >= VK_API_VERSION_1_1 && ComputeQueueFamily(devices[i])) {
      usable.push_back(i);
    }
  }
  if (usable.empty()) {
    return absl::FailedPreconditionError(StrCat(
        "no Vulkan 1.1 device with a compute queue (found: ", names.empty() ? "none" : names,
        "); install mesa-vulkan-drivers for lavapipe"));
  }
  size_t chosen = usable.front();
  if (!selector.empty()) {
    const bool numeric = std::all_of(selector.begin(), selector.end(), ::isdigit);
    auto match = std::find_if(usable.begin(), usable.end(), [&](size_t i) {
      if (numeric) return std::to_string(i) == selector;
      return Lower(devices[i].getProperties().deviceName.data()).find(Lower(selector)) !=
             std::string::npos;
    });
    if (match == usable.end()) {
      return absl::NotFoundError(StrCat("no Vulkan device matches VPM_VULKAN_DEVICE='",
                                              selector, "' (devices: ", names, ")"));
    }
    chosen = *match;
  } else {
    chosen = *std::min_element(usable.begin(), usable.end(), [&](size_t a, size_t b) {
      return DeviceTypeRank(devices[a].getProperties().deviceType) <
             DeviceTypeRank(devices[b].getProperties().deviceType);
    });
  }
  physical_device_ = std::move(devices[chosen]);
  properties_ = physical_device_.getProperties();
  memory_properties_ = physical_device_.getMemoryProperties();
  device_name_ = properties_.deviceName.data();
  queue_family_ = *ComputeQueueFamily(physical_device_);
  const auto family = physical_device_.getQueueFamilyProperties()[queue_family_];
  timestamp_period_ns_ = family.timestampValidBits > 0 ? properties_.limits.timestampPeriod : 0.0;
  return absl::OkStatus();
}

Result<uint32_t> GpuContext::FindMemoryType(uint32_t type_bits, vk::MemoryPropertyFlags required,
                                            vk::MemoryPropertyFlags preferred) const {
  for (const vk::MemoryPropertyFlags want : {required | preferred, required}) {
    for (uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i) {
      if ((type_bits & (1u << i)) &&
          (memory_properties_.memoryTypes[i].propertyFlags & want) == want) {
        return i;
      }
    }
  }
  return absl::ResourceExhaustedError(
      StrCat("no Vulkan memory type with flags ", vk::to_string(required)));
}

vk::MemoryPropertyFlags GpuContext::memory_flags(uint32_t type_index) const {
  return memory_properties_.memoryTypes[type_index].propertyFlags;
}

const vk::raii::CommandPool& GpuContext::ThreadCommandPool() const {
  std::lock_guard lock(pools_mutex_);
  auto& pool = thread_pools_[std::this_thread::get_id()];
  if (!pool) {
    pool = std::make_unique<vk::raii::CommandPool>(
        device_, vk::CommandPoolCreateInfo{vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                                           queue_family_});
  }
  return *pool;
}

vk::raii::CommandBuffer GpuContext::AllocateCommandBuffer() const {
  vk::CommandBufferAllocateInfo info(*ThreadCommandPool(), vk::CommandBufferLevel::ePrimary, 1);
  return std::move(vk::raii::CommandBuffers(device_, info).front());
}

Status GpuContext::SubmitAndWait(const vk::raii::CommandBuffer& commands) const {
  return CatchVulkan("submitting GPU work", [&] {
    vk::raii::Fence fence(device_, vk::FenceCreateInfo{});
    vk::SubmitInfo submit({}, {}, *commands);
    {
      std::lock_guard lock(queue_mutex_);
      queue_.submit(submit, *fence);
    }
    constexpr uint64_t kTimeoutNs = 60'000'000'000;  // a minute: a hung device, not slow work
    if (device_.waitForFences(*fence, VK_TRUE, kTimeoutNs) != vk::Result::eSuccess) {
      throw std::runtime_error("GPU work did not finish within 60 s");
    }
  });
}

Status GpuContext::RunCommands(
    const std::function<void(const vk::raii::CommandBuffer&)>& record) const {
  std::optional<vk::raii::CommandBuffer> commands;  // this thread's pool
  RETURN_IF_ERROR(CatchVulkan("recording GPU commands", [&] {
    commands.emplace(AllocateCommandBuffer());
    commands->begin({vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
    record(*commands);
    commands->end();
  }));
  return SubmitAndWait(*commands);
}

std::vector<std::string> GpuContext::validation_messages() const {
  std::lock_guard lock(messages_mutex_);
  return messages_;
}

void GpuContext::ClearValidationMessages() {
  std::lock_guard lock(messages_mutex_);
  messages_.clear();
}

uint64_t GpuContext::process_validation_message_count() { return g_validation_messages.load(); }

void GpuContext::RecordValidationMessage(std::string message) {
  g_validation_messages.fetch_add(1);
  std::lock_guard lock(messages_mutex_);
  messages_.push_back(std::move(message));
}

}  // namespace vpm::gpu

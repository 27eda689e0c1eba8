#include "tests/gpu/gpu_test_context.h"

#include <cstdlib>
#include <filesystem>
#include <memory>

// Under AddressSanitizer, GPU test binaries never unload a shared library:
// the Vulkan loader unloads its driver and layers at vkDestroyInstance, and
// LeakSanitizer, which runs at exit, then sees their process-lifetime
// allocations as leaks from "<unknown module>", which no suppression can name
// and which cannot be told from ours. Kept mapped, they stay reachable from
// the libraries' globals (or are suppressed by library name in
// scripts/sanitizer-suppressions/lsan.supp). This definition interposes
// libc's for the whole binary; it exists only in sanitizer builds.
#if defined(__SANITIZE_ADDRESS__)
extern "C" int dlclose(void* /*handle*/) { return 0; }
#endif

namespace vpm::testing {
namespace {

bool ValidationLayerInstalled() {
  for (const char* dir : {"/usr/share/vulkan/explicit_layer.d", "/etc/vulkan/explicit_layer.d",
                          "/usr/local/share/vulkan/explicit_layer.d"}) {
    if (std::filesystem::exists(std::filesystem::path(dir) / "VkLayer_khronos_validation.json")) {
      return true;
    }
  }
  return false;
}

std::unique_ptr<gpu::GpuContext>& Slot() {
  static std::unique_ptr<gpu::GpuContext> context;
  return context;
}

class GpuEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    Slot().reset();
    EXPECT_EQ(gpu::GpuContext::process_validation_message_count(), 0u)
        << "Vulkan validation reported messages (see stderr)";
  }
};

const auto* const kEnvironment = ::testing::AddGlobalTestEnvironment(new GpuEnvironment);

}  // namespace

gpu::GpuContext& TestGpuContext() {
  auto& slot = Slot();
  if (!slot) {
    gpu::GpuContext::Options options;
    // Where the layer is installed, a test run without it would hide errors.
    options.enable_validation = ValidationLayerInstalled();
    options.require_validation = options.enable_validation;
    auto context = gpu::GpuContext::Create(options);
    if (!context.ok()) {
      std::cerr << "cannot create the Vulkan context: " << context.status() << "\n";
      std::abort();
    }
    slot = std::move(*context);
  }
  return *slot;
}

void GpuTest::TearDown() {
  const auto messages = context().validation_messages();
  EXPECT_TRUE(messages.empty()) << messages.size() << " validation messages, first: "
                                << (messages.empty() ? "" : messages.front());
}

}  // namespace vpm::testing

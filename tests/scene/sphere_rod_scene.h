// The render tests' synthetic volume (render_test_util.h) with what the GPU
// tests need around it: its upload and a renderer.
#pragma once

#include <memory>

#include "server/common/status.h"
#include "server/gpu/gpu_context.h"
#include "server/raycast/volume_renderer.h"
#include "server/volume/gpu_volume.h"
#include "tests/raycast/render_test_util.h"

namespace vpm::testing {

struct SphereRodScene {
  Volume volume;
  GpuVolume gpu_volume;
  std::unique_ptr<VolumeRenderer> renderer;
};

inline Result<std::unique_ptr<SphereRodScene>> MakeSphereRodScene(const gpu::GpuContext& context) {
  Volume volume = MakeSphereRodVolume();
  ASSIGN_OR_RETURN(GpuVolume gpu_volume, GpuVolume::Upload(context, volume));
  ASSIGN_OR_RETURN(auto renderer, VolumeRenderer::Create(context, {}));
  return std::make_unique<SphereRodScene>(
      SphereRodScene{std::move(volume), std::move(gpu_volume), std::move(renderer)});
}

}  // namespace vpm::testing

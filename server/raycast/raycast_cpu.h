// The ray caster in plain C++: the test oracle and the benchmark baseline of
// shaders/raycast_body.glsl. Same rays, sampling positions, trilinear reads,
// lookup table, shading, compositing, early termination and empty-space
// skipping, in float, in the same order, on `threads` threads (rows
// interleaved).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/gpu/shader_interface.h"
#include "server/raycast/brick_occupancy_cpu.h"
#include "server/raycast/render_presets.h"
#include "server/raycast/render_request.h"
#include "server/volume/volume.h"

namespace vpm {

// A backward map on the host: dims M grid points, texels (X(p) - p mm,
// inside), x fastest; the layout of the GPU image (shaders/backward_map.glsl).
struct HostBackwardMap {
  std::array<int, 3> dims{0, 0, 0};
  std::vector<glm::vec4> texels;
};

struct RaycastCpuInputs {
  const Volume* volume = nullptr;
  const HostBackwardMap* map = nullptr;        // needed when params flag a map
  const RenderLut* lut = nullptr;
  std::span<const float> occupancy;            // needed when params flag skipping
  // BakePreintegratedLut of the same preset and step; needed when params
  // flag kRaycastPreintegrated.
  const std::vector<glm::vec4>* preintegrated = nullptr;
};

// One packed RGBA8 word per pixel (r in the low byte), params.image.xy
// pixels, row 0 at the top. `samples` (optional) receives the samples taken.
std::vector<uint32_t> RaycastCpu(const gpu::RaycastParams& params, const RaycastCpuInputs& in,
                                 int threads, int64_t* samples = nullptr);

// A whole frame on the CPU, as VolumeRenderer::Render: the request's GPU
// handles are ignored; `volume` is the source and `map` (optional) the
// backward map. `brick_minmax` may hold BrickMinMaxCpu(volume,
// RequestBrickVoxels(request, volume.geometry())) to save its cost (InvalidArgument when its
// size is not that brick grid's); timings are wall clock (occupancy_ms, raycast_ms, upscale_ms).
Result<Frame> RenderReference(const RenderRequest& request, const Volume& volume,
                              const HostBackwardMap* map, int threads = 2,
                              const std::vector<glm::vec2>* brick_minmax = nullptr);

}  // namespace vpm

// The CPU reference of shaders/upscale.comp: an interactive frame cast at
// a fraction of the view's size, resized to it (docs/RENDERING.md,
// "Interactive quality").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/gpu/shader_interface.h"

namespace vpm {

// Resize of packed RGBA8 (r in the low byte, row 0 at the top), as
// upscale.comp: filter gpu::kUpscaleBilinear or gpu::kUpscaleCatmullRom.
std::vector<uint32_t> UpscaleCpu(std::span<const uint32_t> source, int source_width,
                                 int source_height, int target_width, int target_height,
                                 int filter = gpu::kUpscaleBilinear);

}  // namespace vpm

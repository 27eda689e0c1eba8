// 3D Slicer's volume rendering presets, by their Slicer names, written from
// the control points Slicer publishes (Modules/Loadable/VolumeRendering/
// Resources/presets.xml): CT-AAA, CT-Bone, CT-Muscle,
// CT-Chest-Contrast-Enhanced, CT-Soft-Tissue, MR-Default. Values in HU for
// CT (the MR preset in the scanner's units, 0..1024), opacity per mm as
// Slicer's (render_transfer_function.h), with Slicer's lighting.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "server/io/render_transfer_function.h"

namespace vpm {

// Names with a one-line description each, in Slicer's order.
std::vector<std::pair<std::string, std::string>> SlicerPresetNames();

// The preset named `name` (case as Slicer writes it), or nullopt.
std::optional<RenderTransferFunction> SlicerPreset(std::string_view name);

}  // namespace vpm

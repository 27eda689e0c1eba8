// A rendering transfer function from a file, by its name: what `--render-tf`
// takes.
//   FILE.json          ParaView colour-map presets, the first entry
//   FILE.json#NAME     ... the entry named NAME
//   FILE.vp, FILE.txt  a 3D Slicer volume property
#pragma once

#include <string_view>

#include "server/common/status.h"
#include "server/io/render_transfer_function.h"

namespace vpm {

// Errors: those of ReadParaviewPreset and ReadSlicerVolumeProperty, and
// InvalidArgument for another extension (Slicer's newer .vp.json included:
// save the property as .vp) or a '#NAME' after a Slicer file.
Result<RenderTransferFunction> ReadRenderTransferFunction(std::string_view spec);

}  // namespace vpm

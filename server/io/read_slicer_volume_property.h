// 3D Slicer's volume property files (.vp), as vtkMRMLVolumePropertyStorageNode
// writes them: nine lines,
//   1 interpolation type (0 nearest, 1 linear)
//   2 shade (0 or 1)
//   3 diffuse   4 ambient   5 specular   6 specular power
//   7 scalar opacity:   N x0 a0 x1 a1 ...        (N numbers follow: 2 per point)
//   8 gradient opacity: N g0 a0 g1 a1 ...
//   9 colour transfer:  N x0 r0 g0 b0 x1 ...     (N numbers follow: 4 per point)
// the same strings as the scalarOpacity / gradientOpacity / colorTransfer
// attributes of Slicer's presets.xml. Values are the volume's (HU for CT),
// opacity per unit distance (1 mm, render_transfer_function.h).
//
// vpm renders colour and scalar opacity; the lighting lines are kept in
// RenderTransferFunction::lighting, the gradient opacity is checked and
// dropped (vpm's shading already fades in homogeneous tissue;
// docs/RENDERING.md).
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"
#include "server/io/render_transfer_function.h"

namespace vpm {

// One of Slicer's function strings "N v0 v1 ..." with N a multiple of
// `stride` (2: piecewise function, 4: colour transfer function): the N
// numbers. InvalidArgument (starting with `what`) for a count that does not
// match, a word that is not a number, NaN or infinity, or more than
// kMaxRenderTfPoints points.
Result<std::vector<double>> ParseSlicerFunctionString(std::string_view line, int stride,
                                                      std::string_view what);

// `text`: the file's content; `name` becomes the function's name; `what`
// names the source in messages. InvalidArgument naming the line for a
// missing line, a malformed number, a count that does not match, unsorted
// or out-of-range points.
Result<RenderTransferFunction> ParseSlicerVolumeProperty(std::string_view text,
                                                         std::string_view name,
                                                         std::string_view what);

// The file at `path` (at most kMaxRenderTfFileBytes), named after its stem.
Result<RenderTransferFunction> ReadSlicerVolumeProperty(const std::string& path);

}  // namespace vpm

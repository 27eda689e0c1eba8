// ParaView's colour-map presets (the JSON that "Export" in ParaView's colour
// map editor writes, and ParaView's own ColorMaps.json): a JSON array of
// objects (a single object is taken as an array of one) with
//   "Name"        string
//   "ColorSpace"  "RGB", "HSV", "Lab", "Diverging", ... (read, see below)
//   "RGBPoints"   [x, r, g, b, ...]   colour control points, x ascending
//   "Points"      [x, alpha, midpoint, sharpness, ...]   opacity, optional
// Values are the volume's own (absolute, HU for CT): vpm does not rescale a
// preset to the data range as ParaView can.
//
// Differences from ParaView, stated in docs/RENDERING.md: colours are
// interpolated in RGB whatever the ColorSpace (ParaView's HSV, Lab and
// Diverging interpolate in those spaces; between close control points the
// difference is small); an opacity segment with a midpoint other than 0.5 or
// a sharpness other than 0 is sampled at 16 points of VTK's curve
// (vtkPiecewiseFunction), a sharpness above 0.99 becomes a step. Without
// "Points" the opacity is ParaView's default, a ramp 0 -> 1 over the colour
// points' range.
#pragma once

#include <string>
#include <string_view>

#include "server/common/status.h"
#include "server/io/render_transfer_function.h"

namespace vpm {

// `text`: the JSON; `name`: the entry to take ("": the first); `what` names
// the source in messages. Errors: InvalidArgument naming what is wrong (not
// JSON, no such name, a missing or malformed key, NaN, unsorted or too many
// points), listing the names the file holds when `name` is not one of them.
Result<RenderTransferFunction> ParseParaviewPreset(std::string_view text, std::string_view name,
                                                   std::string_view what);

// The file at `path` (at most kMaxRenderTfFileBytes): NotFound when missing.
Result<RenderTransferFunction> ReadParaviewPreset(const std::string& path, std::string_view name);

}  // namespace vpm

// A render preset from a transfer function read from another tool
// (RenderTransferFunction: colour and opacity on their own control points)
// or one of Slicer's presets: the colour and the opacity are merged into one
// list of RGBA points on the union of their control values, which is exact:
// both stay piecewise linear between neighbouring points of the union. A
// step (two points at one value) stays a step.
//
// The opacity is already per mm (the preset's convention), so the lookup
// table's step correction a_step = 1 - (1 - a)^(step_mm / 1 mm)
// (BakeRenderLut) applies unchanged.
#pragma once

#include "server/common/status.h"
#include "server/io/render_transfer_function.h"
#include "server/raycast/render_presets.h"
#include "server/volume/volume.h"

namespace vpm {

// Name: tf.name ("custom" when empty). MIP window: VolumeMipWindow(volume).
// Shading half on at 30 HU/mm for CT (IsCtInHu), else at the window width /
// 50 per mm (as mri-t1). Lighting: tf.lighting's where it has one. Still
// step 0.5 x the smallest spacing. Errors: those of
// ValidateRenderTransferFunction.
Result<RenderPreset> RenderPresetFromTf(const RenderTransferFunction& tf, const Volume& volume);

}  // namespace vpm

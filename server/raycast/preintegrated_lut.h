// The pre-integrated transfer function (Engel, Kraus and Ertl 2001): for a
// ray segment of one step along which the value runs linearly from a front
// value to a back value, the colour and opacity of the whole segment,
// integrated front to back with the preset's opacity per mm. A ray then
// sees a sharp transfer function (an opaque surface at -160 HU, a thin band
// of contrast) where the value crosses it, not only where a sample happens
// to land: the step shows neither as rings nor as noise
// (docs/RENDERING.md, "Sampling").
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "server/raycast/render_presets.h"

namespace vpm {

// Inputs: a valid preset (ValidateRenderPreset), step_mm > 0. Output:
// gpu::kPreintegratedEntries^2 entries, index front + N * back, each
// (premultiplied r, g, b, opacity) of one step; entry e of either axis is
// the value lo + e (hi - lo) / (N - 1) over the preset's range [lo, hi] (the
// RenderLut's). A segment of n entries is integrated in n sub-segments, one
// per entry, each at the preset's value at its midpoint; n = 0 is the
// point value over the whole step (as BakeRenderLut).
std::vector<glm::vec4> BakePreintegratedLut(const RenderPreset& preset, double step_mm);

// A step of the table shortened to `fraction` (in [0, 1]) of its length as
// a step of constant value would be: opacity 1 - (1 - a)^fraction, the
// premultiplied colour scaled with it (by `fraction` where a is under
// 1e-6). A ray's partial first and last steps (RaycastSettings::
// partial_end_steps); exact for a constant value. The shader's
// composite_partial_step() computes the same, by exp2 and log2.
glm::vec4 PartialPreintegratedStep(glm::vec4 step, float fraction);

// The table at (front, back) values, bilinear between entries: the shader's
// preintegrated_at(). lut: the RenderLut of the same preset (its range).
glm::vec4 SamplePreintegratedLut(const std::vector<glm::vec4>& table, const RenderLut& lut,
                                 float front, float back);

}  // namespace vpm

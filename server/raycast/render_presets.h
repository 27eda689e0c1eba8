// Rendering presets: colour and opacity transfer functions for DVR (piecewise
// linear RGBA over the volume's values, HU for CT) and a window for MIP, and
// their bake into the lookup table the ray caster reads.
//
// Opacity is given per millimetre of material (`a` = opacity of a 1 mm
// slab), so a preset looks the same at every sampling step and voxel size;
// the bake applies the step correction a_step = 1 - (1 - a)^(step_mm / 1 mm)
// once per (preset, step), so neither the shader nor the CPU reference takes
// a pow per sample, and both read the same table.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/io/render_transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

inline constexpr double kOpacityReferenceMm = 1.0;
// A merged transfer function has at most two points per control value of
// its colour and opacity lists (render_preset_from_tf.h).
inline constexpr size_t kMaxRenderPresetPoints = 4 * kMaxRenderTfPoints;

struct ColorPoint {
  double value = 0.0;      // volume value (HU for CT)
  glm::dvec4 rgba{0.0};    // colour in [0, 1]; a = opacity of 1 mm, in [0, 1]
  bool operator==(const ColorPoint&) const = default;
};

// MIP shows clamp((max - (level - width / 2)) / width, 0, 1) as grey.
struct MipWindow {
  double level = 0.0;
  double width = 1.0;  // > 0
  bool operator==(const MipWindow&) const = default;
};

struct RenderPreset {
  std::string name;
  std::vector<ColorPoint> points;  // at least 2, sorted by value
  MipWindow mip_window;            // the default MIP window for this preset
  // Gradient magnitude (value/mm) at which DVR shading is half on: weaker
  // gradients (noise inside homogeneous tissue) shade less. > 0.
  double shading_gradient = 30.0;
  // Still DVR frames sample every still_step_factor x the smallest voxel
  // spacing (kStill's default step; RaycastSettings::step_mm overrides).
  // 0.5 unless a preset's picture was measured to hold at a larger step
  // (ct-soft-tissue: 1.0, docs/RENDERING.md "Still step per preset").
  // In (0, 4].
  double still_step_factor = 0.5;
  // The lighting the preset was made with (Slicer's presets and .vp files):
  // replaces RaycastSettings' shading on/off, ambient, diffuse, specular and
  // shininess (Slicer's specular power). nullopt: RaycastSettings'.
  std::optional<TfLighting> lighting;
  bool operator==(const RenderPreset&) const = default;
};

// Names with a one-line description each: vpm's ct-soft-tissue, ct-bone,
// ct-vessels, mri-t1, auto, then 3D Slicer's (slicer_presets.h: CT-AAA, CT-Bone,
// ...; names are case-sensitive, so ct-bone and CT-Bone are two presets).
std::vector<std::pair<std::string, std::string>> RenderPresetNames();

// "auto" (or empty): the preset a volume opens with, DefaultRenderPresetName.
inline constexpr std::string_view kAutoRenderPreset = "auto";

// ct-soft-tissue for CT in HU, mri-t1 for any other volume (IsCtInHu,
// server/volume/ct_in_hu.h): the CT presets are in HU, and on an MRI they
// show nothing of its anatomy.
std::string_view DefaultRenderPresetName(const Volume& volume);

// A named preset ("auto" or empty: DefaultRenderPresetName's). mri-t1 is
// defined on intensity percentiles of `volume`
// (p5 transparent up to p99.5 brightest), the CT presets in HU. Every
// preset's MIP window is VolumeMipWindow(volume) (the volume's own
// percentiles, volume_mip_window.h). Errors: InvalidArgument for an unknown
// name, listing the valid ones.
Result<RenderPreset> MakeRenderPreset(std::string_view name, const Volume& volume);

// InvalidArgument unless: 2..kMaxRenderPresetPoints points, finite values
// sorted ascending, colours and opacities in [0, 1], window level finite and
// width > 0, lighting (if any) in [0, 1] with shininess in [1, 256].
Status ValidateRenderPreset(const RenderPreset& preset);
// InvalidArgument unless the level is finite and the width finite and > 0
// (MIP windows and slice windows alike).
Status ValidateMipWindow(const MipWindow& window);

// The lookup table of a preset for one sampling step: kRenderLutEntries
// entries evenly over [first point's value, last point's value]; entry i at
// value_lo + i / entries_per_value; values outside clamp to the end entries.
struct RenderLut {
  float value_lo = 0.0f;
  float entries_per_value = 1.0f;
  std::vector<glm::vec4> entries;      // rgb, opacity for the step
  // nonzero_prefix[i]: how many of entries[0..i) have opacity > 0
  // (entries.size() + 1 values); lets a brick test "any opacity over
  // [min, max]" in O(1).
  std::vector<int32_t> nonzero_prefix;
};

// Preset must be valid (ValidateRenderPreset); step_mm > 0.
RenderLut BakeRenderLut(const RenderPreset& preset, double step_mm);

// The table at `value`, linear between entries: the shader's lut_at().
glm::vec4 SampleRenderLut(const RenderLut& lut, float value);

// Entry index range [lo, hi] that values in [min_value, max_value] touch
// (linear interpolation reads entries floor(f) and floor(f) + 1).
std::pair<int, int> LutEntryRange(const RenderLut& lut, float min_value, float max_value);

}  // namespace vpm

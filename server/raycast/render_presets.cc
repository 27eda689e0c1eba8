#include "server/raycast/render_presets.h"

#include <algorithm>
#include <cmath>

#include "server/gpu/shader_interface.h"
#include "server/raycast/render_preset_from_tf.h"
#include "server/raycast/slicer_presets.h"
#include "server/raycast/volume_mip_window.h"

namespace vpm {
namespace {

using glm::dvec4;

// CT soft tissue, the default: what a cut through the abdomen shows
// (SceneView::view_cut, on in every client's first frame) reads like a
// coloured slice in depth. Fat yellow and translucent, so that organs
// embedded in it show through a few millimetres of it; unenhanced
// parenchyma (kidney, 30 HU) dark red; blood, muscle and liver (45-65 HU)
// turning orange, so the vessels and the muscle stand apart from the
// kidney; enhancing tissue and contrast vessels (150-300 HU) bright red to
// pink; bone ivory. Issue 29: the earlier table painted kidney and fat the
// same red, and a 15 mm kidney drag was hard to see.
RenderPreset CtSoftTissue() {
  RenderPreset preset = {"ct-soft-tissue",
          {{-1000, dvec4(0.0, 0.0, 0.0, 0.0)},
           {-400, dvec4(0.95, 0.85, 0.35, 0.0)},
           {-180, dvec4(0.95, 0.85, 0.35, 0.02)},
           {-100, dvec4(0.98, 0.88, 0.38, 0.12)},
           {-50, dvec4(0.95, 0.80, 0.40, 0.15)},
           {0, dvec4(0.70, 0.30, 0.22, 0.35)},
           {25, dvec4(0.58, 0.10, 0.10, 0.6)},
           {40, dvec4(0.72, 0.22, 0.15, 0.6)},
           {60, dvec4(0.95, 0.62, 0.30, 0.6)},
           {100, dvec4(0.98, 0.65, 0.45, 0.6)},
           {150, dvec4(0.85, 0.05, 0.10, 0.7)},
           {300, dvec4(1.0, 0.70, 0.70, 0.8)},
           {400, dvec4(1.0, 0.95, 0.85, 0.9)},
           {3000, dvec4(1.0, 0.97, 0.90, 0.9)}}};
  preset.still_step_factor = 1.0;
  return preset;
}

// CT bone: everything below 230 HU transparent (the aorta at 210 HU and the
// kidney cortex at 160 HU stay out), cancellous bone ivory, cortex opaque.
RenderPreset CtBone() {
  return {"ct-bone",
          {{-1000, dvec4(0.0, 0.0, 0.0, 0.0)},
           {230, dvec4(0.85, 0.70, 0.50, 0.0)},
           {300, dvec4(0.92, 0.85, 0.70, 0.5)},
           {700, dvec4(1.0, 0.98, 0.92, 1.0)},
           {3000, dvec4(1.0, 0.98, 0.92, 1.0)}}};
}

// CT angiography: contrast-filled vessels (150-260 HU) red and fairly
// opaque; the enhancing kidney cortex (160 HU) falls in the same range and
// shows with them; bone faint ivory for orientation; soft tissue hidden.
RenderPreset CtVessels() {
  return {"ct-vessels",
          {{-1000, dvec4(0.0, 0.0, 0.0, 0.0)},
           {110, dvec4(0.70, 0.05, 0.05, 0.0)},
           {150, dvec4(0.85, 0.12, 0.10, 0.25)},
           {200, dvec4(0.95, 0.18, 0.12, 0.6)},
           {260, dvec4(1.0, 0.30, 0.20, 0.6)},
           {290, dvec4(0.90, 0.85, 0.75, 0.08)},
           {700, dvec4(1.0, 0.97, 0.90, 0.3)},
           {3000, dvec4(1.0, 0.97, 0.90, 0.3)}}};
}

// MRI T1 on the volume's own percentiles: greyscale warming towards white,
// transparent below p5.
RenderPreset MriT1(const Volume& volume) {
  struct Anchor {
    double percentile;
    dvec4 rgba;
  };
  const Anchor anchors[] = {{5.0, dvec4(0.0, 0.0, 0.0, 0.0)},
                            {30.0, dvec4(0.35, 0.33, 0.30, 0.005)},
                            {60.0, dvec4(0.65, 0.62, 0.58, 0.02)},
                            {90.0, dvec4(0.95, 0.90, 0.85, 0.08)},
                            {99.5, dvec4(1.0, 1.0, 1.0, 0.15)}};
  std::vector<float> sample = SampleVolumeValues(volume, -INFINITY);
  std::vector<double> percentiles;
  for (const Anchor& a : anchors) percentiles.push_back(a.percentile);
  const std::vector<double> at = Percentiles(sample, percentiles);
  RenderPreset preset{"mri-t1", {}, {}, 30.0};
  double last = -INFINITY;
  for (size_t i = 0; i < at.size(); ++i) {
    // Strictly increasing, so that flat images still give a valid preset.
    const double v = at[i] <= last ? last + 1e-3 : at[i];
    preset.points.push_back({v, anchors[i].rgba});
    last = v;
  }
  // CT's 30 HU/mm is about 1/50 of the soft tissue to bone range per mm.
  preset.shading_gradient = std::max(1e-6, VolumeMipWindow(volume).width / 50.0);
  return preset;
}

bool InUnit(double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; }

bool InUnit(const dvec4& c) { return InUnit(c.r) && InUnit(c.g) && InUnit(c.b) && InUnit(c.a); }

// A named preset (vpm's or Slicer's), before its MIP window is set.
Result<RenderPreset> VpmPreset(std::string_view name, const Volume& volume) {
  if (name == "ct-soft-tissue") return CtSoftTissue();
  if (name == "ct-bone") return CtBone();
  if (name == "ct-vessels") return CtVessels();
  if (name == "mri-t1") return MriT1(volume);
  if (auto slicer = SlicerPreset(name)) return RenderPresetFromTf(*slicer, volume);
  std::string names;
  for (const auto& [n, _] : RenderPresetNames()) names += (names.empty() ? "" : ", ") + n;
  return absl::InvalidArgumentError(
      StrCat("unknown render preset '", name, "': use one of ", names));
}

}  // namespace

std::vector<std::pair<std::string, std::string>> RenderPresetNames() {
  std::vector<std::pair<std::string, std::string>> names = {
      {"ct-soft-tissue",
       "CT: fat yellow, kidney and parenchyma dark red, blood, muscle and liver orange, "
       "contrast red, bone ivory"},
      {"ct-bone", "CT: bone only (>= 230 HU), cortex opaque"},
      {"ct-vessels", "CT angiography: contrast vessels and kidney cortex red, bone faint"},
      {"mri-t1", "MRI T1: greyscale on the volume's percentiles (p5 transparent .. p99.5)"},
      {"auto", "by the image: ct-soft-tissue on CT in HU, mri-t1 otherwise"},
  };
  for (auto& slicer : SlicerPresetNames()) names.push_back(std::move(slicer));
  return names;
}

std::string_view DefaultRenderPresetName(const Volume& volume) {
  return IsCtInHu(volume) ? "ct-soft-tissue" : "mri-t1";
}

Result<RenderPreset> MakeRenderPreset(std::string_view name, const Volume& volume) {
  if (name.empty() || name == kAutoRenderPreset) name = DefaultRenderPresetName(volume);
  ASSIGN_OR_RETURN(RenderPreset preset, VpmPreset(name, volume));
  preset.mip_window = VolumeMipWindow(volume);
  return preset;
}

Status ValidateMipWindow(const MipWindow& window) {
  if (!std::isfinite(window.level) || !std::isfinite(window.width) || !(window.width > 0.0)) {
    return absl::InvalidArgumentError(StrCat("window level ", window.level, " width ",
                                             window.width,
                                             ": needs a finite level and width > 0"));
  }
  return absl::OkStatus();
}

Status ValidateRenderPreset(const RenderPreset& preset) {
  if (preset.points.size() < 2 || preset.points.size() > kMaxRenderPresetPoints) {
    return absl::InvalidArgumentError(StrCat("render preset '", preset.name, "' has ",
                                             preset.points.size(), " points; 2..",
                                             kMaxRenderPresetPoints, " expected"));
  }
  for (size_t i = 0; i < preset.points.size(); ++i) {
    const ColorPoint& p = preset.points[i];
    if (!std::isfinite(p.value) || !InUnit(p.rgba)) {
      return absl::InvalidArgumentError(StrCat("render preset '", preset.name, "' point ", i,
                                               ": value must be finite, rgba in [0, 1]"));
    }
    if (i > 0 && p.value < preset.points[i - 1].value) {
      return absl::InvalidArgumentError(
          StrCat("render preset '", preset.name, "': values must be sorted ascending"));
    }
  }
  if (!std::isfinite(preset.shading_gradient) || !(preset.shading_gradient > 0.0)) {
    return absl::InvalidArgumentError(
        StrCat("render preset '", preset.name, "': shading_gradient must be > 0"));
  }
  if (!std::isfinite(preset.still_step_factor) || !(preset.still_step_factor > 0.0) ||
      preset.still_step_factor > 4.0) {
    return absl::InvalidArgumentError(
        StrCat("render preset '", preset.name, "': still_step_factor must be in (0, 4]"));
  }
  if (const auto& l = preset.lighting;
      l && (!InUnit(l->ambient) || !InUnit(l->diffuse) || !InUnit(l->specular) ||
            !std::isfinite(l->specular_power) || l->specular_power < 1.0 ||
            l->specular_power > 256.0)) {
    return absl::InvalidArgumentError(
        StrCat("render preset '", preset.name,
               "': lighting needs ambient, diffuse, specular in [0, 1], power in [1, 256]"));
  }
  const MipWindow& w = preset.mip_window;
  if (!std::isfinite(w.level) || !std::isfinite(w.width) || !(w.width > 0.0)) {
    return absl::InvalidArgumentError(StrCat("render preset '", preset.name,
                                             "': MIP window needs a finite level and width > 0"));
  }
  return absl::OkStatus();
}

RenderLut BakeRenderLut(const RenderPreset& preset, double step_mm) {
  const auto& pts = preset.points;
  const int n = gpu::kRenderLutEntries;
  const double lo = pts.front().value;
  const double hi = std::max(pts.back().value, lo + 1e-3);
  RenderLut lut;
  lut.value_lo = static_cast<float>(lo);
  lut.entries_per_value = static_cast<float>((n - 1) / (hi - lo));
  lut.entries.resize(n);
  lut.nonzero_prefix.assign(n + 1, 0);
  const double exponent = step_mm / kOpacityReferenceMm;
  size_t seg = 0;
  for (int i = 0; i < n; ++i) {
    const double v = lo + (hi - lo) * i / (n - 1);
    while (seg + 2 < pts.size() && v >= pts[seg + 1].value) ++seg;
    const ColorPoint& a = pts[seg];
    const ColorPoint& b = pts[seg + 1];
    const double width = b.value - a.value;
    const double t = width > 0.0 ? std::clamp((v - a.value) / width, 0.0, 1.0)
                                 : (v >= b.value ? 1.0 : 0.0);
    const dvec4 c = a.rgba + (b.rgba - a.rgba) * t;
    const double alpha = c.a >= 1.0 ? 1.0 : 1.0 - std::pow(1.0 - c.a, exponent);
    lut.entries[i] = glm::vec4(c.r, c.g, c.b, alpha);
    lut.nonzero_prefix[i + 1] = lut.nonzero_prefix[i] + (lut.entries[i].a > 0.0f ? 1 : 0);
  }
  return lut;
}

glm::vec4 SampleRenderLut(const RenderLut& lut, float value) {
  const int n = static_cast<int>(lut.entries.size());
  const float f = std::clamp((value - lut.value_lo) * lut.entries_per_value, 0.0f, float(n - 1));
  const int i = std::min(static_cast<int>(f), n - 2);
  const float t = f - static_cast<float>(i);
  return lut.entries[i] + (lut.entries[i + 1] - lut.entries[i]) * t;
}

std::pair<int, int> LutEntryRange(const RenderLut& lut, float min_value, float max_value) {
  const int n = static_cast<int>(lut.entries.size());
  const float f_lo = std::clamp((min_value - lut.value_lo) * lut.entries_per_value, 0.0f,
                                float(n - 1));
  const float f_hi = std::clamp((max_value - lut.value_lo) * lut.entries_per_value, 0.0f,
                                float(n - 1));
  return {std::min(static_cast<int>(f_lo), n - 2), std::min(static_cast<int>(f_hi) + 1, n - 1)};
}

}  // namespace vpm

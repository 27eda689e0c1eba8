// A colour and opacity transfer function for rendering, as the tools that
// write them hold it (ParaView's colour-map presets, 3D Slicer's volume
// properties): colour and opacity are two piecewise-linear functions over the
// volume's values (HU for CT), each with its own control points, clamped to
// their end values outside them (VTK's default).
//
// Opacity is that of a 1 mm slab: VTK's scalar opacity is per unit distance
// (vtkVolumeProperty::ScalarOpacityUnitDistance, 1 world unit by default,
// and the world unit of medical volumes is the millimetre), which is the
// convention of vpm's render presets (server/raycast/render_presets.h).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"

namespace vpm {

// Caps what a file may declare: no real transfer function comes near them.
inline constexpr size_t kMaxRenderTfPoints = 1024;
inline constexpr int64_t kMaxRenderTfFileBytes = int64_t{16} << 20;

struct TfColorPoint {
  double value = 0.0;     // volume value (HU for CT)
  glm::dvec3 rgb{0.0};    // in [0, 1]
  bool operator==(const TfColorPoint&) const = default;
};

struct TfOpacityPoint {
  double value = 0.0;    // volume value
  double opacity = 0.0;  // opacity of a 1 mm slab, in [0, 1]
  bool operator==(const TfOpacityPoint&) const = default;
};

// The lighting a Slicer volume property asks for (not applied by vpm's
// ray caster, which keeps its own headlight: docs/RENDERING.md).
struct TfLighting {
  bool shade = true;
  double ambient = 0.1, diffuse = 0.9, specular = 0.2, specular_power = 10.0;
  bool operator==(const TfLighting&) const = default;
};

struct RenderTransferFunction {
  std::string name;
  std::vector<TfColorPoint> colors;        // 1..kMaxRenderTfPoints, value ascending
  std::vector<TfOpacityPoint> opacities;   // 1..kMaxRenderTfPoints, value ascending
  std::optional<TfLighting> lighting;      // Slicer's .vp only
  bool operator==(const RenderTransferFunction&) const = default;
};

// InvalidArgument, starting with `what` (the file), unless both lists hold
// 1..kMaxRenderTfPoints points with finite values in ascending order (equal
// neighbours allowed: a step) and colours and opacities finite in [0, 1].
Status ValidateRenderTransferFunction(const RenderTransferFunction& tf, std::string_view what);

}  // namespace vpm

#include "server/raycast/render_request.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace vpm {
namespace {

glm::vec4 Vec4(const glm::dvec3& v, double w = 0.0) {
  return glm::vec4(float(v.x), float(v.y), float(v.z), float(w));
}

bool FiniteUnit(double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; }

Status CheckSettings(const RaycastSettings& s) {
  if (!FiniteUnit(s.background.r) || !FiniteUnit(s.background.g) ||
      !FiniteUnit(s.background.b)) {
    return absl::InvalidArgumentError("background colour must be in [0, 1]");
  }
  if (!FiniteUnit(s.ambient) || !FiniteUnit(s.diffuse) || !FiniteUnit(s.specular) ||
      !std::isfinite(s.shininess) || s.shininess < 1.0 || s.shininess > 256.0) {
    return absl::InvalidArgumentError(
        "shading: ambient, diffuse and specular in [0, 1], shininess in [1, 256]");
  }
  if (!std::isfinite(s.step_mm) || s.step_mm < 0.0) {
    return absl::InvalidArgumentError(
        StrCat("step ", s.step_mm, " mm: must be finite and >= 0 (0: default)"));
  }
  return absl::OkStatus();
}

Status CheckInteractiveCast(const InteractiveCast& c) {
  if (!std::isfinite(c.divisor) || c.divisor < 1.0 || c.divisor > kMaxInteractiveDivisor) {
    return absl::InvalidArgumentError(
        StrCat("interactive divisor ", c.divisor, ": must be in 1..", kMaxInteractiveDivisor));
  }
  if (!std::isfinite(c.still_step_multiple) || c.still_step_multiple < 0.0) {
    return absl::InvalidArgumentError(StrCat("interactive step multiple ", c.still_step_multiple,
                                             ": must be finite and >= 0 (0: footprint)"));
  }
  if (c.upscale_filter != gpu::kUpscaleBilinear && c.upscale_filter != gpu::kUpscaleCatmullRom) {
    return absl::InvalidArgumentError(StrCat("upscale filter ", c.upscale_filter, ": unknown"));
  }
  return absl::OkStatus();
}

double StillStepMm(const RenderRequest& request, const VolumeGeometry& geometry) {
  const glm::dvec3& s = geometry.spacing_mm;
  const bool mip = request.mode == RenderMode::kMip;
  const double factor = mip ? kStillMipStepFactor : request.preset.still_step_factor;
  return std::min(factor * std::min({s.x, s.y, s.z}), mip ? kStillMipMaxStepMm : kStillMaxStepMm);
}

}  // namespace

int RenderSide(const RenderRequest& request, int side) {
  if (request.quality != RenderQuality::kInteractive) return side;
  const double d = request.interactive.divisor;
  if (!std::isfinite(d) || d <= 1.0) return side;
  return std::max(1, int(std::ceil(double(side) / std::min(d, kMaxInteractiveDivisor) - 1e-9)));
}

InteractiveCast InteractiveCastFor(InteractiveQuality quality) {
  switch (quality) {
    case InteractiveQuality::kFast:
    case InteractiveQuality::kAuto:
      return {.divisor = 2.0, .still_step_multiple = 0.0, .upscale_filter = gpu::kUpscaleBilinear};
    case InteractiveQuality::kBalanced:
      return {.divisor = 2.0, .still_step_multiple = 2.0, .upscale_filter = gpu::kUpscaleBilinear};
    case InteractiveQuality::kSharp:
      return {.divisor = 1.0, .still_step_multiple = 1.5, .upscale_filter = gpu::kUpscaleBilinear};
  }
  return {};
}

std::optional<InteractiveQuality> InteractiveQualityNamed(std::string_view name) {
  if (name == "auto") return InteractiveQuality::kAuto;
  if (name == "fast") return InteractiveQuality::kFast;
  if (name == "balanced") return InteractiveQuality::kBalanced;
  if (name == "sharp") return InteractiveQuality::kSharp;
  return std::nullopt;
}

int UpscaleFilterOf(const RenderRequest& request) {
  return request.quality == RenderQuality::kInteractive ? request.interactive.upscale_filter
                                                        : gpu::kUpscaleBilinear;
}

glm::ivec3 BrickVoxels(RenderQuality quality, const VolumeGeometry& geometry) {
  const double mm = quality == RenderQuality::kInteractive ? kInteractiveBrickMm : kStillBrickMm;
  glm::ivec3 w;
  for (int a = 0; a < 3; ++a) {
    const double voxels = std::round(mm / geometry.spacing_mm[a]);
    const double most = double(std::max<int64_t>(1, geometry.dims[a] - 1));
    w[a] = int(std::clamp(std::isfinite(voxels) ? voxels : 1.0, 1.0, most));
  }
  return w;
}

glm::ivec3 RequestBrickVoxels(const RenderRequest& request, const VolumeGeometry& geometry) {
  const bool coarse_grid =
      (request.quality == RenderQuality::kInteractive && request.interactive.divisor >= 2.0) ||
      RequestStepMm(request, geometry) >= kCoarseGridStepMm;
  return BrickVoxels(coarse_grid ? RenderQuality::kInteractive : RenderQuality::kStill, geometry);
}

std::array<int, 3> BrickGridDims(const std::array<int64_t, 3>& dims, glm::ivec3 brick_voxels) {
  std::array<int, 3> b{};
  for (int a = 0; a < 3; ++a) {
    const int64_t w = std::max(1, brick_voxels[a]);
    b[a] = std::max<int>(1, int((dims[a] - 1 + w - 1) / w));
  }
  return b;
}

double InteractiveStepMm(const Camera& camera, int render_width, int render_height,
                         const VolumeGeometry& geometry) {
  const glm::dvec3& s = geometry.spacing_mm;
  const double floor_mm = kInteractiveStepFactor * std::min({s.x, s.y, s.z});
  const Camera::Pose& pose = camera.pose();
  const double shorter = double(std::max(1, std::min(render_width, render_height)));
  const double footprint_mm =
      2.0 * pose.distance_mm * std::tan(0.5 * pose.fov_deg * std::numbers::pi / 180.0) / shorter;
  const double ceiling_mm = glm::length(geometry.extent_mm()) / kInteractiveMinSamplesPerRay;
  const double step = std::min(kInteractiveStepPerPixel * footprint_mm, ceiling_mm);
  return std::isfinite(step) ? std::max(floor_mm, step) : floor_mm;
}

double RequestStepMm(const RenderRequest& request, const VolumeGeometry& geometry) {
  if (request.settings.step_mm > 0.0) return request.settings.step_mm;
  if (request.quality == RenderQuality::kInteractive) {
    const double footprint = InteractiveStepMm(request.camera, RenderSide(request, request.width),
                                               RenderSide(request, request.height), geometry);
    const double multiple = request.interactive.still_step_multiple;
    return multiple > 0.0 ? std::min(footprint, multiple * StillStepMm(request, geometry))
                          : footprint;
  }
  return StillStepMm(request, geometry);
}

namespace {

// PrepareRaycast's checks of the request, before anything is computed;
// returns the step (RequestStepMm), checked against kMaxSamplesPerRay.
Result<double> CheckedStepMm(const RenderRequest& request, const VolumeGeometry& geometry,
                             const std::array<int, 3>& map_dims) {
  if (request.width < 1 || request.height < 1 || request.width > kMaxFrameSide ||
      request.height > kMaxFrameSide) {
    return absl::InvalidArgumentError(StrCat("frame size ", request.width, "x", request.height,
                                             ": each side must be in 1..", kMaxFrameSide));
  }
  for (int a = 0; a < 3; ++a) {
    if (geometry.dims[a] < 2) {
      return absl::InvalidArgumentError("ray casting needs at least 2 voxels along each axis");
    }
  }
  RETURN_IF_ERROR(request.camera.Validate());
  RETURN_IF_ERROR(ValidateRenderPreset(request.preset));
  RETURN_IF_ERROR(CheckSettings(request.settings));
  RETURN_IF_ERROR(CheckInteractiveCast(request.interactive));
  RETURN_IF_ERROR(ValidateClipRegion(request.clip));
  RETURN_IF_ERROR(ValidateMipWindow(request.mip_window.value_or(request.preset.mip_window)));
  const double step = RequestStepMm(request, geometry);
  if (glm::length(geometry.extent_mm()) / step > kMaxSamplesPerRay) {
    return absl::InvalidArgumentError(StrCat("step ", step, " mm gives more than ",
                                             kMaxSamplesPerRay, " samples along the diagonal"));
  }
  if (map_dims[0] > 0 && (map_dims[0] < 2 || map_dims[1] < 2 || map_dims[2] < 2)) {
    return absl::InvalidArgumentError("backward map needs at least 2 grid points per axis");
  }
  return step;
}

// The ray caster's flags (gpu::kRaycast*, kRaycastCellGradient,
// kRaycastPreintegrated) for a request.
int RaycastFlags(const RenderRequest& request, bool has_map) {
  const RaycastSettings& s = request.settings;
  const bool interactive = request.quality == RenderQuality::kInteractive;
  // A preset made with its own lighting (Slicer's) brings it along.
  const std::optional<TfLighting>& lighting = request.preset.lighting;
  int flags = 0;
  if (lighting ? lighting->shade : s.shading) flags |= gpu::kRaycastShading;
  if (s.empty_space_skipping) flags |= gpu::kRaycastSkipping;
  if (s.early_termination) flags |= gpu::kRaycastEarlyTermination;
  if (has_map) flags |= gpu::kRaycastHasMap;
  if (s.count_samples) flags |= gpu::kRaycastCountSamples;
  if (s.jitter) flags |= gpu::kRaycastJitter;
  if (s.mip_brightest_first && request.mode == RenderMode::kMip) {
    flags |= gpu::kRaycastBrightestFirst;
  }
  if (s.mip_peak_refine && request.mode == RenderMode::kMip) flags |= gpu::kRaycastPeakRefine;
  if ((interactive ? s.interactive_cell_gradient : s.still_cell_gradient) &&
      request.mode == RenderMode::kDvr) {
    flags |= kRaycastCellGradient;
    if (s.preintegrated) flags |= kRaycastPreintegrated;
    if (s.preintegrated && s.light_both_ends) flags |= gpu::kRaycastLightBothEnds;
    if (s.preintegrated && s.partial_end_steps) flags |= gpu::kRaycastPartialEndSteps;
  }
  return flags;
}

}  // namespace

Result<RaycastSetup> PrepareRaycast(const RenderRequest& request, const VolumeGeometry& geometry,
                                    const std::array<int, 3>& map_dims) {
  ASSIGN_OR_RETURN(const double step, CheckedStepMm(request, geometry, map_dims));
  const MipWindow window = request.mip_window.value_or(request.preset.mip_window);
  RaycastSetup setup;
  setup.step_mm = step;
  setup.render_width = RenderSide(request, request.width);
  setup.render_height = RenderSide(request, request.height);
  const CameraRays rays = request.camera.Rays(setup.render_width, setup.render_height);
  const RaycastSettings& s = request.settings;
  const std::optional<TfLighting>& lighting = request.preset.lighting;
  const int flags = RaycastFlags(request, map_dims[0] > 0);
  const glm::ivec3 brick_voxels = RequestBrickVoxels(request, geometry);
  const auto bricks = BrickGridDims(geometry.dims, brick_voxels);
  gpu::RaycastParams& p = setup.params;
  p.eye_mm = Vec4(rays.eye_mm, step);
  p.forward = Vec4(rays.forward);
  p.right = Vec4(rays.right);
  p.up = Vec4(rays.up);
  p.dims = glm::ivec4(int(geometry.dims[0]), int(geometry.dims[1]), int(geometry.dims[2]),
                      request.mode == RenderMode::kMip ? 1 : 0);
  p.spacing_mm = Vec4(geometry.spacing_mm);
  p.image = glm::ivec4(setup.render_width, setup.render_height, flags,
                       int32_t(s.jitter_seed));
  p.bricks = glm::ivec4(bricks[0], bricks[1], bricks[2], 0);
  p.brick_voxels = glm::ivec4(brick_voxels, 0);
  p.window = glm::vec4(float(window.level - 0.5 * window.width), float(1.0 / window.width),
                       float(window.level + 0.5 * window.width), 0.0f);
  p.background = Vec4(s.background);
  p.shading = lighting ? glm::vec4(float(lighting->ambient), float(lighting->diffuse),
                                   float(lighting->specular), float(lighting->specular_power))
                       : glm::vec4(float(s.ambient), float(s.diffuse), float(s.specular),
                                   float(s.shininess));
  p.map_dims = glm::vec4(float(map_dims[0]), float(map_dims[1]), float(map_dims[2]), 0.0f);
  p.gradient = glm::vec4(float(request.preset.shading_gradient), 0.0f, 0.0f, 0.0f);
  const std::vector<glm::dvec4> planes = ClipPlanesInPhysical(request.clip, geometry);
  static_assert(kMaxClipPlanes == gpu::kRaycastMaxClipPlanes);
  p.clip = glm::ivec4(int(planes.size()), 0, 0, 0);
  for (size_t i = 0; i < planes.size(); ++i) p.clip_planes[i] = glm::vec4(planes[i]);
  return setup;
}

glm::vec4 LutParams(const RenderLut& lut) {
  return glm::vec4(lut.value_lo, lut.entries_per_value, float(lut.entries.size()),
                   float(gpu::kPreintegratedEntries));
}

}  // namespace vpm

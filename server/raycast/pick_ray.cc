#include "server/raycast/pick_ray.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "server/raycast/clip_region.h"

namespace vpm {
namespace {

// Trilinear value at `p` (physical voxel space, mm), clamped indexing.
float SampleAt(const Volume& volume, const glm::dvec3& p) {
  const glm::dvec3 f = p / volume.geometry().spacing_mm;
  const glm::dvec3 base = glm::floor(f);
  const glm::dvec3 t = f - base;
  const int64_t i = int64_t(base.x), j = int64_t(base.y), k = int64_t(base.z);
  double value = 0.0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double w = (dx ? t.x : 1.0 - t.x) * (dy ? t.y : 1.0 - t.y) * (dz ? t.z : 1.0 - t.z);
    value += w * volume.AtClamped(i + dx, j + dy, k + dz);
  }
  return float(value);
}

// Entry and exit ray parameters (mm) of the box of voxel centres
// [0, (n - 1) * spacing]; nullopt on a miss.
std::optional<std::pair<double, double>> ClipToBox(const VolumeGeometry& g, const glm::dvec3& eye,
                                                   const glm::dvec3& dir) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double hi = double(g.dims[a] - 1) * g.spacing_mm[a];
    if (std::abs(dir[a]) < 1e-12) {
      if (eye[a] < 0.0 || eye[a] > hi) return std::nullopt;
      continue;
    }
    double ta = (0.0 - eye[a]) / dir[a], tb = (hi - eye[a]) / dir[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (t0 > t1) return std::nullopt;
  return std::make_pair(t0, t1);
}

}  // namespace

std::optional<glm::dvec3> PickAlongRay(const Volume& volume, const RenderPreset& preset,
                                       RenderMode mode, const glm::dvec3& eye_mm,
                                       const glm::dvec3& direction,
                                       std::span<const glm::dvec4> clip_planes) {
  const VolumeGeometry& g = volume.geometry();
  auto range = ClipToBox(g, eye_mm, direction);
  if (!range) return std::nullopt;
  ClipRayInterval(clip_planes, eye_mm, direction, range->first, range->second);
  if (range->first > range->second) return std::nullopt;
  const double step =
      0.5 * std::min({g.spacing_mm.x, g.spacing_mm.y, g.spacing_mm.z});  // the still step
  const RenderLut lut = BakeRenderLut(preset, step);  // opacity per step
  double transmittance = 1.0;
  float best = -std::numeric_limits<float>::infinity();
  double best_t = -1.0;
  for (double t = range->first; t <= range->second; t += step) {
    const glm::dvec3 p = eye_mm + t * direction;
    const float value = SampleAt(volume, p);
    if (mode == RenderMode::kMip) {
      if (value > best) {
        best = value;
        best_t = t;
      }
      continue;
    }
    transmittance *= 1.0 - double(SampleRenderLut(lut, value).a);
    if (1.0 - transmittance >= kPickOpacity) return p;
  }
  if (mode == RenderMode::kMip && best_t >= 0.0 && best > volume.min_value()) {
    return eye_mm + best_t * direction;
  }
  return std::nullopt;
}

}  // namespace vpm

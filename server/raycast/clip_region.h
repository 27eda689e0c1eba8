// What part of the deformed volume a frame shows: an optional crop box and
// any number of clip planes, in world coordinates (LPS, mm), the frame the
// deformed volume is shown in. A sample at world point x is shown when it
// lies in the box and on the kept side of every plane; the region is convex,
// so each ray keeps one interval of its path (ClipRayInterval), and the ray
// caster only moves its first and last sample.
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Keeps the half space dot(normal, x) >= offset_mm (x world, mm): the normal
// points into what stays visible. Any non-zero normal; used normalised.
struct ClipPlane {
  glm::dvec3 normal{0.0, 0.0, 1.0};
  double offset_mm = 0.0;
};

// Keeps lo_mm <= x <= hi_mm per world axis (LPS, mm).
struct CropBox {
  glm::dvec3 lo_mm{0.0};
  glm::dvec3 hi_mm{0.0};
};

struct ClipRegion {
  std::optional<CropBox> crop;
  std::vector<ClipPlane> planes;

  bool empty() const { return !crop && planes.empty(); }
};

// Planes the ray caster takes per frame (gpu::RaycastParams::clip_planes);
// a crop box counts as six.
inline constexpr int kMaxClipPlanes = 16;

// InvalidArgument for a non-finite number, a zero normal, a box with
// lo > hi on an axis, or more than kMaxClipPlanes planes (box included).
Status ValidateClipRegion(const ClipRegion& region);

// The region as half spaces of physical voxel space (mm, index * spacing:
// where the ray caster works): each (n, d) keeps dot(n, p) >= d, n unit.
// Box faces first (-x.. +z order of lo then hi per axis), then the planes.
std::vector<glm::dvec4> ClipPlanesInPhysical(const ClipRegion& region,
                                             const VolumeGeometry& geometry);

// Narrows the ray eye + t dir (t in [t_near, t_far]) to the part that keeps
// dot(n, x) >= d for every plane (n, d) in `planes`; t_near > t_far after it
// when nothing is left. Single precision as shaders/raycast_body.glsl (the
// CPU reference of the ray caster); double for picking.
void ClipRayInterval(std::span<const glm::vec4> planes, const glm::vec3& eye,
                     const glm::vec3& dir, float& t_near, float& t_far);
void ClipRayInterval(std::span<const glm::dvec4> planes, const glm::dvec3& eye,
                     const glm::dvec3& dir, double& t_near, double& t_far);

// The plane through `point_world` (LPS, mm) facing away from a camera that
// looks along `forward_world`: keeps what lies beyond the point, so the
// cut face through the point is what the camera sees.
ClipPlane CutPlaneFacing(const glm::dvec3& point_world, const glm::dvec3& forward_world);

}  // namespace vpm

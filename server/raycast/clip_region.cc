#include "server/raycast/clip_region.h"

#include <cmath>

#include "server/common/finite_vec3.h"

namespace vpm {
namespace {

// The half space dot(n, x) >= d of world space, in physical space: x = o + D p
// gives dot(D^T n, p) >= d - dot(n, o); D is orthonormal, so D^T n stays unit.
glm::dvec4 ToPhysical(const glm::dvec3& normal_world, double offset_mm,
                      const VolumeGeometry& geometry) {
  const glm::dvec3 n = glm::normalize(normal_world);
  const double d = offset_mm / glm::length(normal_world);
  return glm::dvec4(glm::transpose(geometry.direction) * n, d - glm::dot(n, geometry.origin_mm));
}

// ClipRayInterval in float or double; `parallel`: |dot(n, dir)| below which
// the ray runs along the plane.
template <typename Real>
void ClipInterval(std::span<const glm::vec<4, Real>> planes, const glm::vec<3, Real>& eye,
                  const glm::vec<3, Real>& dir, Real parallel, Real& t_near, Real& t_far) {
  for (const glm::vec<4, Real>& plane : planes) {
    const glm::vec<3, Real> n(plane);
    const Real along = glm::dot(n, dir);
    const Real inside = glm::dot(n, eye) - plane.w;  // >= 0: the eye is kept
    if (std::abs(along) < parallel) {
      // Parallel to the plane: all kept or all cut.
      if (inside < Real(0)) t_far = Real(-1);
      continue;
    }
    const Real t = -inside / along;
    if (along > Real(0)) {
      t_near = std::max(t_near, t);
    } else {
      t_far = std::min(t_far, t);
    }
  }
}

}  // namespace

Status ValidateClipRegion(const ClipRegion& region) {
  int count = static_cast<int>(region.planes.size());
  if (region.crop) {
    count += 6;
    const CropBox& box = *region.crop;
    if (!IsFinite(box.lo_mm) || !IsFinite(box.hi_mm)) {
      return absl::InvalidArgumentError("crop box: corners must be finite numbers (mm)");
    }
    for (int a = 0; a < 3; ++a) {
      if (box.lo_mm[a] > box.hi_mm[a]) {
        return absl::InvalidArgumentError(
            StrCat("crop box: ", "xyz"[a], " from ", box.lo_mm[a], " to ", box.hi_mm[a],
                   " mm is empty (the first corner must be the lower one)"));
      }
    }
  }
  for (size_t i = 0; i < region.planes.size(); ++i) {
    const ClipPlane& plane = region.planes[i];
    if (!IsFinite(plane.normal) || !std::isfinite(plane.offset_mm)) {
      return absl::InvalidArgumentError(
          StrCat("clip plane ", i + 1, ": normal and offset must be finite numbers"));
    }
    if (!(glm::length(plane.normal) > 1e-12)) {
      return absl::InvalidArgumentError(StrCat("clip plane ", i + 1, ": the normal is zero"));
    }
  }
  if (count > kMaxClipPlanes) {
    return absl::InvalidArgumentError(
        StrCat(count, " clip planes (a crop box counts 6): at most ", kMaxClipPlanes));
  }
  return absl::OkStatus();
}

std::vector<glm::dvec4> ClipPlanesInPhysical(const ClipRegion& region,
                                             const VolumeGeometry& geometry) {
  std::vector<glm::dvec4> out;
  if (region.crop) {
    for (int a = 0; a < 3; ++a) {
      glm::dvec3 axis(0.0);
      axis[a] = 1.0;
      out.push_back(ToPhysical(axis, region.crop->lo_mm[a], geometry));
      out.push_back(ToPhysical(-axis, -region.crop->hi_mm[a], geometry));
    }
  }
  for (const ClipPlane& plane : region.planes) {
    out.push_back(ToPhysical(plane.normal, plane.offset_mm, geometry));
  }
  return out;
}

void ClipRayInterval(std::span<const glm::vec4> planes, const glm::vec3& eye, const glm::vec3& dir,
                     float& t_near, float& t_far) {
  ClipInterval(planes, eye, dir, 1e-20f, t_near, t_far);
}

void ClipRayInterval(std::span<const glm::dvec4> planes, const glm::dvec3& eye,
                     const glm::dvec3& dir, double& t_near, double& t_far) {
  ClipInterval(planes, eye, dir, 1e-12, t_near, t_far);
}

ClipPlane CutPlaneFacing(const glm::dvec3& point_world, const glm::dvec3& forward_world) {
  const glm::dvec3 n = glm::normalize(forward_world);
  return ClipPlane{n, glm::dot(n, point_world)};
}

}  // namespace vpm

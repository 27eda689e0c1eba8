#include "client/view/clip_plane_drag.h"

#include <algorithm>
#include <limits>

namespace vpm::view {
namespace {

glm::dvec3 UnitNormal(const v3::ClipPlane& plane) {
  const glm::dvec3 n{plane.normal().x(), plane.normal().y(), plane.normal().z()};
  const double length = glm::length(n);
  return length > 0.0 ? n / length : glm::dvec3(0.0, 0.0, 1.0);
}

}  // namespace

v3::ClipPlane ClipPlaneFacingCamera(const ViewCamera& camera, const VolumeGeometry& geometry) {
  const glm::dvec3 n = glm::normalize(geometry.direction * camera.camera().Forward());
  const glm::dvec3 target = geometry.PhysicalToWorld(camera.camera().Target());
  v3::ClipPlane plane;
  plane.mutable_normal()->set_x(n.x);
  plane.mutable_normal()->set_y(n.y);
  plane.mutable_normal()->set_z(n.z);
  plane.set_offset_mm(glm::dot(n, target));
  return plane;
}

v3::ClipPlane MoveClipPlane(const v3::ClipPlane& plane, double delta_mm, const WorldBox& box) {
  const glm::dvec3 n = UnitNormal(plane);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner{(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                            (c & 4) ? box.hi.z : box.lo.z};
    lo = std::min(lo, glm::dot(n, corner));
    hi = std::max(hi, glm::dot(n, corner));
  }
  // The offset of the unit normal's plane (the proto's normal may have any length).
  const double length = glm::length(
      glm::dvec3{plane.normal().x(), plane.normal().y(), plane.normal().z()});
  const double offset = length > 0.0 ? plane.offset_mm() / length : plane.offset_mm();
  v3::ClipPlane out;
  out.mutable_normal()->set_x(n.x);
  out.mutable_normal()->set_y(n.y);
  out.mutable_normal()->set_z(n.z);
  out.set_offset_mm(std::clamp(offset + delta_mm, lo, hi));
  return out;
}

double ClipDragMm(const ViewCamera& camera, const VolumeGeometry& geometry,
                  const v3::ClipPlane& plane, double dx_px, double dy_px, int frame_width,
                  int frame_height) {
  const glm::dvec3 n_physical = glm::transpose(geometry.direction) * UnitNormal(plane);
  return camera.MotionAlongMm(n_physical, dx_px, dy_px, frame_width, frame_height);
}

}  // namespace vpm::view

#include "client/view/crop_box_drag.h"

#include <algorithm>
#include <limits>

namespace vpm::view {
namespace {

glm::dvec3 Corner(const WorldBox& box, int c) {
  return {(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
          (c & 4) ? box.hi.z : box.lo.z};
}

v3::Vec3 ToVec3(const glm::dvec3& v) {
  v3::Vec3 out;
  out.set_x(v.x);
  out.set_y(v.y);
  out.set_z(v.z);
  return out;
}

}  // namespace

WorldBox VolumeWorldBox(const VolumeGeometry& geometry) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  WorldBox box{glm::dvec3(kInf), glm::dvec3(-kInf)};
  const glm::dvec3 extent = geometry.extent_mm();
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 p{(c & 1) ? extent.x : 0.0, (c & 2) ? extent.y : 0.0,
                       (c & 4) ? extent.z : 0.0};
    const glm::dvec3 w = geometry.PhysicalToWorld(p);
    box.lo = glm::min(box.lo, w);
    box.hi = glm::max(box.hi, w);
  }
  return box;
}

v3::CropBox CropBoxToProto(const WorldBox& box) {
  v3::CropBox out;
  *out.mutable_lo_mm() = ToVec3(box.lo);
  *out.mutable_hi_mm() = ToVec3(box.hi);
  return out;
}

std::optional<BoxFace> PickBoxFace(const ViewCamera& camera, const VolumeGeometry& geometry,
                                   const WorldBox& box, int px, int py, int frame_width,
                                   int frame_height) {
  if (px < 0 || py < 0 || px >= frame_width || py >= frame_height) return std::nullopt;
  const CameraRays rays = camera.camera().Rays(frame_width, frame_height);
  const glm::dvec3 eye = geometry.PhysicalToWorld(rays.eye_mm);
  const glm::dvec3 dir = geometry.direction * rays.Direction(px, py);
  // Slabs: the ray is inside the box for t in [t_in, t_out].
  double t_in = -std::numeric_limits<double>::infinity();
  double t_out = std::numeric_limits<double>::infinity();
  BoxFace in_face, out_face;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(dir[a]) < 1e-12) {
      if (eye[a] < box.lo[a] || eye[a] > box.hi[a]) return std::nullopt;
      continue;
    }
    const double t_lo = (box.lo[a] - eye[a]) / dir[a];
    const double t_hi = (box.hi[a] - eye[a]) / dir[a];
    // Moving along +a the ray enters at lo and leaves at hi.
    const BoxFace enter{a, dir[a] < 0.0}, leave{a, dir[a] > 0.0};
    const double t_enter = std::min(t_lo, t_hi), t_leave = std::max(t_lo, t_hi);
    if (t_enter > t_in) t_in = t_enter, in_face = enter;
    if (t_leave < t_out) t_out = t_leave, out_face = leave;
  }
  if (!(t_in <= t_out) || t_out < 0.0) return std::nullopt;
  return t_in >= 0.0 ? in_face : out_face;
}

WorldBox MoveBoxFace(const WorldBox& start, BoxFace face, double delta_mm, const WorldBox& limits,
                     double min_gap_mm) {
  WorldBox box = start;
  const int a = face.axis;
  if (face.high) {
    box.hi[a] = std::clamp(start.hi[a] + delta_mm, std::min(start.lo[a] + min_gap_mm, limits.hi[a]),
                           limits.hi[a]);
  } else {
    box.lo[a] = std::clamp(start.lo[a] + delta_mm, limits.lo[a],
                           std::max(start.hi[a] - min_gap_mm, limits.lo[a]));
  }
  return box;
}

double FaceDragMm(const ViewCamera& camera, const VolumeGeometry& geometry, BoxFace face,
                  double dx_px, double dy_px, int frame_width, int frame_height) {
  glm::dvec3 axis_world(0.0);
  axis_world[face.axis] = 1.0;
  // Physical direction of the world axis (direction is orthonormal).
  const glm::dvec3 axis_physical = glm::transpose(geometry.direction) * axis_world;
  return camera.MotionAlongMm(axis_physical, dx_px, dy_px, frame_width, frame_height);
}

std::vector<ScreenSegment> BoxOutline(const ViewCamera& camera, const VolumeGeometry& geometry,
                                      const WorldBox& box, std::optional<BoxFace> highlight,
                                      int frame_width, int frame_height) {
  std::array<std::optional<glm::dvec3>, 8> screen;
  for (int c = 0; c < 8; ++c) {
    screen[c] = camera.camera().Project(geometry.WorldToPhysical(Corner(box, c)), frame_width,
                                        frame_height);
  }
  std::vector<ScreenSegment> out;
  for (int c = 0; c < 8; ++c) {
    for (int a = 0; a < 3; ++a) {
      const int d = c | (1 << a);
      if (d == c || !screen[c] || !screen[d]) continue;
      // The edge runs along a; it borders the face (f, high) when both ends
      // sit on that side of axis f != a.
      bool on_face = false;
      if (highlight && highlight->axis != a) {
        on_face = (((c >> highlight->axis) & 1) != 0) == highlight->high;
      }
      out.push_back({glm::dvec2(*screen[c]), glm::dvec2(*screen[d]), on_face});
    }
  }
  return out;
}

}  // namespace vpm::view

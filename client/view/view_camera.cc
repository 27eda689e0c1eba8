#include "client/view/view_camera.h"

#include <cmath>

namespace vpm::view {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

}  // namespace

Result<VolumeGeometry> GeometryFromProto(const v3::VolumeInfo& info) {
  if (info.dims_size() != 3) {
    return absl::InvalidArgumentError(
        StrCat("volume ", info.volume_id(), ": ", info.dims_size(), " dims, expected 3"));
  }
  VolumeGeometry g;
  for (int a = 0; a < 3; ++a) {
    if (info.dims(a) < 1) {
      return absl::InvalidArgumentError(StrCat("volume ", info.volume_id(), ": dims[", a, "] = ",
                                               info.dims(a), ", must be >= 1"));
    }
    g.dims[a] = info.dims(a);
  }
  g.spacing_mm = {info.spacing_mm().x(), info.spacing_mm().y(), info.spacing_mm().z()};
  if (!(g.spacing_mm.x > 0 && g.spacing_mm.y > 0 && g.spacing_mm.z > 0)) {
    return absl::InvalidArgumentError(StrCat("volume ", info.volume_id(), ": spacing must be > 0"));
  }
  g.origin_mm = {info.origin_lps_mm().x(), info.origin_lps_mm().y(), info.origin_lps_mm().z()};
  if (info.direction_size() == 9) {
    for (int c = 0; c < 3; ++c) {
      for (int r = 0; r < 3; ++r) g.direction[c][r] = info.direction(c * 3 + r);
    }
  } else if (info.direction_size() != 0) {
    return absl::InvalidArgumentError(StrCat("volume ", info.volume_id(), ": ",
                                             info.direction_size(), " direction values, expected 9"));
  }
  return g;
}

ViewCamera::ViewCamera(const VolumeGeometry& geometry)
    : geometry_(geometry), camera_(Camera::ForVolume(geometry)) {}

void ViewCamera::Orbit(double dx_px, double dy_px) {
  camera_.Orbit(-dx_px * kOrbitDegPerPixel, dy_px * kOrbitDegPerPixel);
}

void ViewCamera::Zoom(double clicks) { camera_.Zoom(std::pow(kZoomPerWheelClick, clicks)); }

void ViewCamera::Pan(double dx_px, double dy_px, int frame_width, int frame_height) {
  // Moving the orbit centre against the mouse makes the picture follow it.
  const double mm = MmPerPixel(frame_width, frame_height);
  camera_.Pan(-dx_px * mm, dy_px * mm);
}

void ViewCamera::Reset() { camera_.Reset(); }

v3::Camera ViewCamera::ToProto() const {
  const Camera::Pose& p = camera_.pose();
  v3::Camera out;
  out.set_azimuth_deg(p.azimuth_deg);
  out.set_elevation_deg(p.elevation_deg);
  out.set_distance_mm(p.distance_mm);
  out.mutable_pan_mm()->set_x(p.pan_mm.x);
  out.mutable_pan_mm()->set_y(p.pan_mm.y);
  return out;
}

double ViewCamera::MmPerPixel(int frame_width, int frame_height) const {
  // The field of view spans the shorter side (Camera::Rays).
  const Camera::Pose& p = camera_.pose();
  const double shorter = std::max(1, std::min(frame_width, frame_height));
  return 2.0 * p.distance_mm * std::tan(0.5 * p.fov_deg * kDegToRad) / shorter;
}

glm::dvec3 ViewCamera::DragOffsetMm(double dx_px, double dy_px, int frame_width,
                                    int frame_height) const {
  const double mm = MmPerPixel(frame_width, frame_height);
  return mm * (dx_px * camera_.Right() - dy_px * camera_.Up());
}

double ViewCamera::MotionAlongMm(const glm::dvec3& direction_mm, double dx_px, double dy_px,
                                 int frame_width, int frame_height) const {
  const double length = glm::length(direction_mm);
  if (!(length > 0.0)) return 0.0;
  const glm::dvec3 n = direction_mm / length;
  const double mm = MmPerPixel(frame_width, frame_height);
  // 1 mm along n moves its image by s / mm pixels (right, down).
  const glm::dvec2 s{glm::dot(n, camera_.Right()), -glm::dot(n, camera_.Up())};
  const double s2 = glm::dot(s, s);
  if (s2 < 0.04) {
    const double away = glm::dot(n, camera_.Forward()) >= 0.0 ? 1.0 : -1.0;
    return -dy_px * mm * away;
  }
  return mm * glm::dot(glm::dvec2{dx_px, dy_px}, s) / s2;
}

std::optional<glm::dvec3> ViewCamera::PickPoint(int px, int py, int frame_width,
                                                int frame_height) const {
  if (px < 0 || py < 0 || px >= frame_width || py >= frame_height) return std::nullopt;
  const CameraRays rays = camera_.Rays(frame_width, frame_height);
  const glm::dvec3 dir = rays.Direction(px, py);
  const glm::dvec3 forward = camera_.Forward();
  const double t = glm::dot(camera_.Target() - rays.eye_mm, forward) / glm::dot(dir, forward);
  const glm::dvec3 p = rays.eye_mm + t * dir;
  const glm::dvec3 extent = geometry_.extent_mm();
  for (int a = 0; a < 3; ++a) {
    if (!(p[a] >= 0.0 && p[a] <= extent[a])) return std::nullopt;
  }
  return p;
}

}  // namespace vpm::view

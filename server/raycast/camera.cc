#include "server/raycast/camera.h"

#include <algorithm>
#include <cmath>

namespace vpm {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

bool Finite(const glm::dvec2& v) { return std::isfinite(v.x) && std::isfinite(v.y); }

}  // namespace

glm::dvec3 CameraRays::Direction(int px, int py) const {
  const double nx = 2.0 * (px + 0.5) / width - 1.0;
  const double ny = 1.0 - 2.0 * (py + 0.5) / height;
  return glm::normalize(forward + nx * right + ny * up);
}

Camera::Camera(const VolumeGeometry& geometry, Pose home) : home_(home), pose_(home) {
  // Physical direction of a world (LPS) direction w: D^T w.
  const glm::dmat3 to_physical = glm::transpose(geometry.direction);
  anterior_ = glm::normalize(to_physical * glm::dvec3(0.0, -1.0, 0.0));
  left_ = glm::normalize(to_physical * glm::dvec3(1.0, 0.0, 0.0));
  superior_ = glm::normalize(to_physical * glm::dvec3(0.0, 0.0, 1.0));
  handedness_ = glm::determinant(geometry.direction) < 0.0 ? -1.0 : 1.0;
  centre_mm_ = 0.5 * geometry.extent_mm();
}

Camera Camera::ForVolume(const VolumeGeometry& geometry) {
  Camera camera(geometry, Pose{});
  // Smallest distance at which every corner of the box lies inside the
  // field of view: |lateral| <= (distance + depth) * tan(fov / 2).
  const glm::dvec3 extent = geometry.extent_mm();
  const double tan_half = std::tan(0.5 * camera.pose_.fov_deg * kDegToRad);
  const glm::dvec3 f = camera.Forward(), u = camera.Up(), r = camera.Right();
  double distance = 0.0;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec3 corner((c & 1) ? extent.x : 0.0, (c & 2) ? extent.y : 0.0,
                            (c & 4) ? extent.z : 0.0);
    const glm::dvec3 v = corner - camera.centre_mm_;
    const double lateral = std::max(std::abs(glm::dot(v, r)), std::abs(glm::dot(v, u)));
    distance = std::max(distance, lateral / tan_half - glm::dot(v, f));
  }
  camera.home_.distance_mm = std::max(1.05 * distance, 1e-3);
  camera.pose_ = camera.home_;
  return camera;
}

void Camera::Orbit(double delta_azimuth_deg, double delta_elevation_deg) {
  pose_.azimuth_deg = std::remainder(pose_.azimuth_deg + delta_azimuth_deg, 360.0);
  pose_.elevation_deg = std::remainder(pose_.elevation_deg + delta_elevation_deg, 360.0);
}

void Camera::Pan(double right_mm, double up_mm) { pose_.pan_mm += glm::dvec2(right_mm, up_mm); }

void Camera::Zoom(double factor) {
  if (factor > 0.0) pose_.distance_mm /= factor;
}

void Camera::Reset() { pose_ = home_; }

Status Camera::Validate() const {
  const Pose& p = pose_;
  if (!std::isfinite(p.azimuth_deg) || !std::isfinite(p.elevation_deg) ||
      !std::isfinite(p.distance_mm) || !Finite(p.pan_mm) || !std::isfinite(p.fov_deg)) {
    return absl::InvalidArgumentError("camera: azimuth, elevation, distance, pan and field of "
                                      "view must be finite numbers");
  }
  if (!(p.distance_mm > 0.0)) {
    return absl::InvalidArgumentError(StrCat("camera distance ", p.distance_mm,
                                             " mm: must be > 0"));
  }
  if (p.fov_deg < 1.0 || p.fov_deg > 170.0) {
    return absl::InvalidArgumentError(StrCat("camera field of view ", p.fov_deg,
                                             " degrees: must be in [1, 170]"));
  }
  return absl::OkStatus();
}

glm::dvec3 Camera::Forward() const {
  const double az = pose_.azimuth_deg * kDegToRad, el = pose_.elevation_deg * kDegToRad;
  const glm::dvec3 horizontal = std::cos(az) * anterior_ + std::sin(az) * left_;
  return -(std::cos(el) * horizontal + std::sin(el) * superior_);
}

glm::dvec3 Camera::Up() const {
  const double az = pose_.azimuth_deg * kDegToRad, el = pose_.elevation_deg * kDegToRad;
  const glm::dvec3 horizontal = std::cos(az) * anterior_ + std::sin(az) * left_;
  return -std::sin(el) * horizontal + std::cos(el) * superior_;
}

// The world cross product maps to physical space with a sign flip when the
// direction matrix mirrors: (D a) x (D b) = det(D) D (a x b).
glm::dvec3 Camera::Right() const { return handedness_ * glm::cross(Forward(), Up()); }

glm::dvec3 Camera::Target() const {
  return centre_mm_ + pose_.pan_mm.x * Right() + pose_.pan_mm.y * Up();
}

glm::dvec3 Camera::Eye() const { return Target() - pose_.distance_mm * Forward(); }

CameraRays Camera::Rays(int width, int height) const {
  CameraRays rays;
  rays.width = width;
  rays.height = height;
  const double tan_half = std::tan(0.5 * pose_.fov_deg * kDegToRad);
  const double shorter = std::max(1, std::min(width, height));
  rays.eye_mm = Eye();
  rays.forward = Forward();
  rays.right = Right() * (tan_half * width / shorter);
  rays.up = Up() * (tan_half * height / shorter);
  return rays;
}

std::optional<glm::dvec3> Camera::Project(const glm::dvec3& p_mm, int width, int height) const {
  const CameraRays rays = Rays(width, height);
  const glm::dvec3 v = p_mm - rays.eye_mm;
  const double depth = glm::dot(v, rays.forward);
  if (!(depth > 0.0)) return std::nullopt;
  // rays.right and rays.up are orthogonal to forward and to each other.
  const double nx = glm::dot(v, rays.right) / (depth * glm::dot(rays.right, rays.right));
  const double ny = glm::dot(v, rays.up) / (depth * glm::dot(rays.up, rays.up));
  return glm::dvec3((nx + 1.0) * 0.5 * width, (1.0 - ny) * 0.5 * height, depth);
}

}  // namespace vpm

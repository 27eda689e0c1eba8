// A perspective orbit camera around the centre of a volume's image box, in
// physical voxel space (mm, index * spacing; docs/ALGORITHM.md section 0).
//
// Orientation is anatomical, taken from the volume's direction matrix, so a
// volume stored in any axis order shows the same default view:
//  - azimuth 0, elevation 0 is the anterior view: the camera sits in front
//    of the patient (world -y in LPS) looking posterior (+y), superior (+z)
//    up, so the patient's left appears on the right of the image;
//  - azimuth turns the camera about the superior axis towards the patient's
//    left (90: left lateral view, 180: posterior view);
//  - elevation raises it towards superior (90: looking down from the head).
// Pan moves the orbit centre in the view plane (mm); zoom divides the
// distance. The field of view spans the shorter image side, so the whole box
// stays in view for any aspect ratio.
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// Everything the ray caster needs to make one ray per pixel: the ray of pixel
// (px, py), row 0 at the top, is eye + t * normalize(forward + ndc.x * right +
// ndc.y * up), ndc = (2 (px + 0.5) / width - 1, 1 - 2 (py + 0.5) / height).
struct CameraRays {
  glm::dvec3 eye_mm{0.0};
  glm::dvec3 forward{0.0, 1.0, 0.0};  // unit
  glm::dvec3 right{1.0, 0.0, 0.0};    // right * tan(fov/2) * width / shorter side
  glm::dvec3 up{0.0, 0.0, 1.0};       // up * tan(fov/2) * height / shorter side
  int width = 0;
  int height = 0;

  glm::dvec3 Direction(int px, int py) const;  // unit
};

class Camera {
 public:
  struct Pose {
    double azimuth_deg = 0.0;
    double elevation_deg = 0.0;
    double distance_mm = 1.0;      // eye to orbit centre
    glm::dvec2 pan_mm{0.0, 0.0};   // orbit centre offset along (right, up)
    double fov_deg = 30.0;         // across the shorter image side
  };

  // Identity-direction frame centred at the origin, distance 1 mm: a
  // placeholder; real cameras come from ForVolume.
  Camera() = default;

  // The default view of `geometry`: anterior, head up, the whole image box
  // in view (distance fitted to the box's eight corners, 5% margin).
  static Camera ForVolume(const VolumeGeometry& geometry);

  void Orbit(double delta_azimuth_deg, double delta_elevation_deg);
  void Pan(double right_mm, double up_mm);
  // factor > 1 moves closer (distance / factor); factor must be > 0.
  void Zoom(double factor);
  void Reset();  // back to ForVolume's pose

  const Pose& pose() const { return pose_; }
  void set_pose(const Pose& pose) { pose_ = pose; }

  // InvalidArgument unless every number is finite, distance > 0 and the
  // field of view is in [1, 170] degrees.
  Status Validate() const;

  // Physical-space frame of the current pose.
  glm::dvec3 Target() const;   // orbit centre + pan (mm)
  glm::dvec3 Eye() const;      // mm
  glm::dvec3 Forward() const;  // unit, eye to target
  glm::dvec3 Up() const;       // unit, orthogonal to Forward
  glm::dvec3 Right() const;    // unit, Forward x Up in world (LPS) terms

  CameraRays Rays(int width, int height) const;

  // Image position of physical point p for a width x height image: x, y in
  // pixels (pixel (i, j) covers [i, i+1) x [j, j+1)), z = depth along the
  // view direction (mm). Empty when p is not in front of the eye.
  std::optional<glm::dvec3> Project(const glm::dvec3& p_mm, int width, int height) const;

 private:
  Camera(const VolumeGeometry& geometry, Pose home);
  // Unit anatomical directions in physical space.
  glm::dvec3 anterior_{0.0, -1.0, 0.0};
  glm::dvec3 left_{1.0, 0.0, 0.0};
  glm::dvec3 superior_{0.0, 0.0, 1.0};
  double handedness_ = 1.0;  // det(direction): -1 when it mirrors
  glm::dvec3 centre_mm_{0.0};
  Pose home_{};
  Pose pose_{};
};

}  // namespace vpm

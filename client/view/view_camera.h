// The viewer's copy of the session camera, kept in step with the server's
// (server/raycast/camera.h, the same class): mouse motion in window pixels
// becomes orbit angles, zoom factors, pan and drag offsets in mm, and a
// click becomes the point the server's pick will grab.
//
// Units: angles in degrees, lengths in mm, points in physical voxel space
// (index * spacing, mm: the camera's frame; the viewer turns them into the
// API's world LPS with the volume's geometry before sending), pixels of the
// frame the server renders (width x height, row 0 at the top).
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/raycast/camera.h"
#include "server/volume/volume.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

// How far one pixel of mouse motion turns the camera (degrees) and how much
// one wheel click zooms (distance divided by this per click).
inline constexpr double kOrbitDegPerPixel = 0.4;
inline constexpr double kZoomPerWheelClick = 1.1;

// dims, spacing, origin and direction (9 values, column-major) of `info`.
// InvalidArgument when a field is missing or not positive.
Result<VolumeGeometry> GeometryFromProto(const v3::VolumeInfo& info);

class ViewCamera {
 public:
  // The server's default view of the volume (Camera::ForVolume).
  explicit ViewCamera(const VolumeGeometry& geometry);

  // dx, dy: mouse motion in pixels (right, down). Dragging right turns the
  // volume to the right (the camera towards the patient's right), dragging
  // down tips its top towards the viewer.
  void Orbit(double dx_px, double dy_px);
  // clicks > 0 (wheel up) moves closer.
  void Zoom(double clicks);
  // The point under the cursor in the orbit-centre plane follows the mouse;
  // frame_width x frame_height is the size of the frame being shown.
  void Pan(double dx_px, double dy_px, int frame_width, int frame_height);
  void Reset();

  v3::Camera ToProto() const;
  const Camera& camera() const { return camera_; }

  // mm covered by one frame pixel in the plane through the orbit centre
  // that faces the camera (where the server's pick puts the grab).
  double MmPerPixel(int frame_width, int frame_height) const;
  // Screen motion (pixels, right and down) to a drag offset in physical
  // space: along the view's right and up axes, at the grab plane's scale.
  glm::dvec3 DragOffsetMm(double dx_px, double dy_px, int frame_width, int frame_height) const;
  // The point Grab{pick, px, py} grabs (the pixel's ray meets the plane
  // through the orbit centre that faces the camera), or empty when that
  // point is outside the volume's box and the server would refuse it.
  std::optional<glm::dvec3> PickPoint(int px, int py, int frame_width, int frame_height) const;
  // How far (mm, signed) a point at the orbit centre's depth moves along
  // `direction_mm` (physical, any length > 0) to follow a screen motion of
  // (dx, dy) pixels (right, down): the motion's component along the
  // direction's image on screen. When the direction points almost along the
  // view (its image is under a fifth of its length), dragging up moves it
  // away from the viewer instead. Used to drag crop faces and clip planes.
  double MotionAlongMm(const glm::dvec3& direction_mm, double dx_px, double dy_px,
                       int frame_width, int frame_height) const;

 private:
  VolumeGeometry geometry_;
  Camera camera_;
};

}  // namespace vpm::view

// Dragging the faces of the crop box in vpm-view's 3D view
// (RenderSettings.crop): which face the ray of a frame pixel meets, how a
// mouse drag moves it along its normal, and the box's outline on screen.
//
// Units: the box is world (LPS) mm, as RenderSettings.crop; frame pixels as
// ViewCamera (row 0 at the top); the camera lives in physical voxel space
// and `geometry` maps between the two.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "client/view/view_camera.h"
#include "server/volume/volume.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

// An axis-aligned box in world mm, lo <= hi per axis.
struct WorldBox {
  glm::dvec3 lo{0.0};
  glm::dvec3 hi{0.0};
};

// The world box around the volume's voxel centres (all 8 corners of the
// index box mapped to world, then their bounds).
WorldBox VolumeWorldBox(const VolumeGeometry& geometry);

v3::CropBox CropBoxToProto(const WorldBox& box);

// One face: the faces at lo[axis] (high = false) and hi[axis] (high = true).
struct BoxFace {
  int axis = 0;
  bool high = false;
  bool operator==(const BoxFace&) const = default;
};

// The face through which the ray of frame pixel (px, py) enters `box`
// (leaves it, when the eye is inside); empty when the ray misses the box.
std::optional<BoxFace> PickBoxFace(const ViewCamera& camera, const VolumeGeometry& geometry,
                                   const WorldBox& box, int px, int py, int frame_width,
                                   int frame_height);

// `start` with `face` moved by `delta_mm` along +axis, kept inside `limits`
// and at least `min_gap_mm` from the opposite face.
WorldBox MoveBoxFace(const WorldBox& start, BoxFace face, double delta_mm, const WorldBox& limits,
                     double min_gap_mm = 1.0);

// How far (mm along +axis) a screen motion of (dx, dy) frame pixels moves
// `face` (ViewCamera::MotionAlongMm on the face's world axis).
double FaceDragMm(const ViewCamera& camera, const VolumeGeometry& geometry, BoxFace face,
                  double dx_px, double dy_px, int frame_width, int frame_height);

// The box's 12 edges on screen, frame pixels; edges with an end behind the
// eye are left out. `on_face`: the edge borders `highlight`.
struct ScreenSegment {
  glm::dvec2 a{0.0};
  glm::dvec2 b{0.0};
  bool on_face = false;
};
std::vector<ScreenSegment> BoxOutline(const ViewCamera& camera, const VolumeGeometry& geometry,
                                      const WorldBox& box, std::optional<BoxFace> highlight,
                                      int frame_width, int frame_height);

}  // namespace vpm::view

// The clip plane of vpm-view's 3D view (RenderSettings.clip): placed facing
// the camera through the orbit centre, keeping what lies beyond it, then
// moved along its normal by a drag or by keys.
//
// Units: planes in world (LPS) mm, dot(normal, x) >= offset_mm kept, normal
// unit; frame pixels as ViewCamera.
#pragma once

#include "client/view/crop_box_drag.h"
#include "client/view/view_camera.h"
#include "server/volume/volume.h"
#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

// The plane through the camera's target (orbit centre + pan) whose normal is
// the view direction: what lies in front of the target is cut away.
v3::ClipPlane ClipPlaneFacingCamera(const ViewCamera& camera, const VolumeGeometry& geometry);

// `plane` moved by `delta_mm` along its normal, kept where it still meets
// `box` (offset within the box corners' range along the normal).
v3::ClipPlane MoveClipPlane(const v3::ClipPlane& plane, double delta_mm, const WorldBox& box);

// How far (mm along the normal) a screen motion of (dx, dy) frame pixels
// moves `plane` (ViewCamera::MotionAlongMm: for a plane facing the camera,
// dragging up cuts deeper).
double ClipDragMm(const ViewCamera& camera, const VolumeGeometry& geometry,
                  const v3::ClipPlane& plane, double dx_px, double dy_px, int frame_width,
                  int frame_height);

}  // namespace vpm::view

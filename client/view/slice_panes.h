// Input on the slice panes of vpm-view's 2 x 2 layout, as pure geometry
// on a slice's SliceGeometry (proto/vpm/v3/vpm.proto): scrolling moves the
// plane along its normal, a press grabs the point of the plane under the
// pointer, moving drags it within the plane (as the web viewer does,
// client/web/public/slice_views.js).
//
// Units: slice pixels are continuous image coordinates (pixel (i, j),
// row 0 at the top, covers [i, i+1) x [j, j+1)); offsets are world mm along
// the slice's normal; points and drag offsets are world LPS mm, as
// Grab.point_mm and Drag.offset_mm.
#pragma once

#include <glm/glm.hpp>

#include "vpm/v3/vpm.pb.h"

namespace vpm::view {

// The plane's offset (SliceSpec.at_mm) after `notches` wheel notches or key
// presses from `at_mm`: one slice pixel (pixel_mm) a notch, towards +normal
// for positive notches, kept where the plane still meets the volume
// ([min_offset_mm, max_offset_mm]).
double ScrolledSliceOffset(const v3::SliceGeometry& geometry, double at_mm, double notches);

// The world point shown at slice pixel coordinates (x, y).
glm::dvec3 SlicePointMm(const v3::SliceGeometry& geometry, double x, double y);

// A motion of (dx, dy) slice pixels (right, down) as a drag offset within
// the plane, world mm.
glm::dvec3 SliceDragOffsetMm(const v3::SliceGeometry& geometry, double dx, double dy);

}  // namespace vpm::view

// vpm-view's slice-pane gestures (client/view/slice_panes.h): scrolling,
// the point a press grabs and the drag within the plane.
#include <gtest/gtest.h>

#include "client/view/slice_panes.h"

namespace vpm::view {
namespace {

void Set(v3::Vec3* v, double x, double y, double z) {
  v->set_x(x);
  v->set_y(y);
  v->set_z(z);
}

// A coronal-like slice: right along +x (0.8 mm a pixel), down along -z.
v3::SliceGeometry Coronal() {
  v3::SliceGeometry g;
  Set(g.mutable_origin_mm(), 10.0, 40.0, 90.0);
  Set(g.mutable_step_u_mm(), 0.8, 0.0, 0.0);
  Set(g.mutable_step_v_mm(), 0.0, 0.0, -0.8);
  g.set_pixel_mm(0.8);
  g.set_offset_mm(-12.0);
  g.set_min_offset_mm(-30.0);
  g.set_max_offset_mm(20.0);
  return g;
}

TEST(SlicePanes, ScrollStepsOnePixelANotchAndStaysOnTheVolume) {
  const v3::SliceGeometry g = Coronal();
  EXPECT_DOUBLE_EQ(ScrolledSliceOffset(g, -12.0, 1.0), -11.2);
  EXPECT_DOUBLE_EQ(ScrolledSliceOffset(g, -12.0, -5.0), -16.0);
  EXPECT_DOUBLE_EQ(ScrolledSliceOffset(g, 19.5, 3.0), 20.0);     // the far end
  EXPECT_DOUBLE_EQ(ScrolledSliceOffset(g, -12.0, -100.0), -30.0);  // the near end
  EXPECT_DOUBLE_EQ(ScrolledSliceOffset(g, 5.0, 0.0), 5.0);
}

TEST(SlicePanes, PixelCentresMapAsSliceGeometrySays) {
  const v3::SliceGeometry g = Coronal();
  // Pixel (i, j) shows origin + (i + 0.5) step_u + (j + 0.5) step_v.
  const glm::dvec3 p = SlicePointMm(g, 3.5, 10.5);
  EXPECT_DOUBLE_EQ(p.x, 10.0 + 3.5 * 0.8);
  EXPECT_DOUBLE_EQ(p.y, 40.0);
  EXPECT_DOUBLE_EQ(p.z, 90.0 - 10.5 * 0.8);
}

TEST(SlicePanes, DragStaysInThePlaneAndFollowsThePixels) {
  const v3::SliceGeometry g = Coronal();
  const glm::dvec3 d = SliceDragOffsetMm(g, 5.0, -2.0);
  EXPECT_DOUBLE_EQ(d.x, 4.0);
  EXPECT_DOUBLE_EQ(d.y, 0.0);  // no motion along the normal
  EXPECT_DOUBLE_EQ(d.z, 1.6);  // up the image: superior
  const glm::dvec3 from = SlicePointMm(g, 7.0, 7.0), to = SlicePointMm(g, 12.0, 5.0);
  EXPECT_NEAR(glm::length(to - from - d), 0.0, 1e-12);
}

}  // namespace
}  // namespace vpm::view

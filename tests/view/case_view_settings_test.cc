// vpm-view opening a case: the case's kept view replaces what the frame
// shows; the viewer's frame size, overlay and encoding stay.
#include "client/view/case_view_settings.h"

#include <gtest/gtest.h>

namespace vpm::view {
namespace {

TEST(CaseViewSettings, TheCasesViewReplacesWhatShowsAndTheViewersFrameStays) {
  v3::RenderSettings own;
  own.set_mode(v3::RENDER_MODE_MIP);
  own.set_width(640);
  own.set_height(480);
  own.set_overlay(true);
  own.set_encoding(v3::ENCODING_JPEG);
  own.set_jpeg_quality(70);
  own.set_interactive_quality(v3::INTERACTIVE_QUALITY_SHARP);
  own.set_view_cut(true);
  own.add_clip()->set_offset_mm(9.0);
  v3::RenderSettings view;
  view.set_preset("ct-bone");
  view.mutable_crop()->mutable_lo_mm()->set_x(-10.5);
  view.mutable_crop()->mutable_hi_mm()->set_z(30.25);
  view.add_slices()->set_view("axial");
  const v3::RenderSettings merged = WithCaseView(own, view);
  EXPECT_EQ(merged.mode(), v3::RENDER_MODE_UNSPECIFIED);  // the case's: DVR
  EXPECT_EQ(merged.preset(), "ct-bone");
  EXPECT_FALSE(merged.view_cut());
  EXPECT_EQ(merged.clip_size(), 0);
  ASSERT_EQ(merged.slices_size(), 1);
  EXPECT_EQ(merged.slices(0).view(), "axial");
  EXPECT_EQ(merged.width(), 640);
  EXPECT_EQ(merged.height(), 480);
  EXPECT_TRUE(merged.overlay());
  EXPECT_EQ(merged.jpeg_quality(), 70);
  EXPECT_EQ(merged.interactive_quality(), v3::INTERACTIVE_QUALITY_SHARP);
  const WorldBox box = CropBoxFromProto(merged.crop());
  EXPECT_EQ(box.lo.x, -10.5);
  EXPECT_EQ(box.hi.z, 30.25);
}

}  // namespace
}  // namespace vpm::view

// SceneHistory: what holds the tissue, folded from every op applied.
#include "server/scene/scene_history.h"

#include <gtest/gtest.h>

namespace vpm {
namespace {

SceneOp Grab(double x) { return {.kind = SceneOp::Kind::kGrab, .grab = {.point_mm = {x, 0, 0}}}; }
SceneOp Drag(double z) { return {.kind = SceneOp::Kind::kDrag, .vector = {0, 0, z}}; }
SceneOp Release(bool keep) { return {.kind = SceneOp::Kind::kRelease, .keep = keep}; }
SceneOp Pin(double x) { return {.kind = SceneOp::Kind::kPin, .vector = {x, 0, 0}}; }

TEST(SceneHistory, KeepsEachGrabsLastDragAndDropsWhatAReleaseLetsGo) {
  const std::vector<SceneOp> folded =
      FoldHistory({Grab(1), Drag(1), Drag(2), Release(true), Pin(5), Grab(7), Drag(3), Drag(4)});
  ASSERT_EQ(folded.size(), 6u);
  EXPECT_EQ(folded[1].vector.z, 2.0);  // the first grab's last drag
  EXPECT_EQ(folded[3].kind, SceneOp::Kind::kPin);
  EXPECT_EQ(folded[5].vector.z, 4.0);
  // A release that does not keep drops its grab and motion; a reset clears.
  EXPECT_EQ(FoldHistory({Grab(1), Drag(1), Release(true), Grab(2), Drag(2), Release(false)}).size(),
            3u);
  EXPECT_TRUE(FoldHistory({Grab(1), Drag(1), {.kind = SceneOp::Kind::kReset}}).empty());
  EXPECT_TRUE(StartsAction(SceneOp::Kind::kPin));
  EXPECT_FALSE(StartsAction(SceneOp::Kind::kRelease));
}

}  // namespace
}  // namespace vpm

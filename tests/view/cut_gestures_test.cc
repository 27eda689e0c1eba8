// vpm-view's crop box and clip plane gestures (client/view/crop_box_drag.h,
// client/view/clip_plane_drag.h) against brute-force references and the
// server's camera projection.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "client/view/clip_plane_drag.h"
#include "client/view/crop_box_drag.h"

namespace vpm::view {
namespace {

constexpr int kCutW = 200, kCutH = 160;  // frame pixels

// A 64 x 48 x 40 volume, rotated 90 degrees about the world z axis and
// mirrored in z, away from the world origin: world and physical differ.
VolumeGeometry Rotated() {
  VolumeGeometry g;
  g.dims = {64, 48, 40};
  g.spacing_mm = {1.5, 2.0, 2.5};
  g.origin_mm = {-40.0, 25.0, 100.0};
  g.direction = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, -1));
  return g;
}

// The smallest t > 0 at which the pixel's ray (world) meets a face of `box`
// inside the face's rectangle, and that face: checks all six faces.
std::optional<BoxFace> NearestFaceByBruteForce(const ViewCamera& c, const VolumeGeometry& g,
                                               const WorldBox& box, int px, int py,
                                               glm::dvec3* hit) {
  const CameraRays rays = c.camera().Rays(kCutW, kCutH);
  const glm::dvec3 eye = g.PhysicalToWorld(rays.eye_mm);
  const glm::dvec3 dir = g.direction * rays.Direction(px, py);
  double best = std::numeric_limits<double>::infinity();
  std::optional<BoxFace> face;
  for (int a = 0; a < 3; ++a) {
    for (bool high : {false, true}) {
      if (dir[a] == 0.0) continue;
      const double t = ((high ? box.hi[a] : box.lo[a]) - eye[a]) / dir[a];
      const glm::dvec3 p = eye + t * dir;
      bool inside = t > 0.0;
      for (int b = 0; b < 3; ++b) {
        if (b != a) inside = inside && p[b] >= box.lo[b] - 1e-9 && p[b] <= box.hi[b] + 1e-9;
      }
      if (inside && t < best) best = t, face = BoxFace{a, high}, *hit = p;
    }
  }
  return face;
}

TEST(CropBoxDrag, VolumeWorldBoxBoundsTheRotatedVolume) {
  const VolumeGeometry g = Rotated();
  const WorldBox box = VolumeWorldBox(g);
  // Axis i (63 x 1.5 mm) runs along world +y, j (47 x 2 mm) along -x, k (39 x 2.5) along -z.
  EXPECT_NEAR(box.lo.x, -40.0 - 94.0, 1e-9);
  EXPECT_NEAR(box.hi.x, -40.0, 1e-9);
  EXPECT_NEAR(box.lo.y, 25.0, 1e-9);
  EXPECT_NEAR(box.hi.y, 25.0 + 94.5, 1e-9);
  EXPECT_NEAR(box.lo.z, 100.0 - 97.5, 1e-9);
  EXPECT_NEAR(box.hi.z, 100.0, 1e-9);
  const v3::CropBox proto = CropBoxToProto(box);
  EXPECT_DOUBLE_EQ(proto.lo_mm().x(), box.lo.x);
  EXPECT_DOUBLE_EQ(proto.hi_mm().z(), box.hi.z);
}

TEST(CropBoxDrag, PickedFaceIsTheNearestOneTheRayMeets) {
  const VolumeGeometry g = Rotated();
  WorldBox box = VolumeWorldBox(g);
  box.lo.x += 10.0;  // a box smaller than the volume: rays miss it near the edges
  box.hi.z -= 20.0;
  int hits = 0, misses = 0;
  for (double azimuth : {0.0, 40.0, 135.0, 250.0}) {
    ViewCamera c(g);
    c.Orbit(azimuth / -kOrbitDegPerPixel, 30.0);
    for (int py = 0; py < kCutH; py += 8) {
      for (int px = 0; px < kCutW; px += 8) {
        glm::dvec3 hit(0.0);
        const std::optional<BoxFace> want = NearestFaceByBruteForce(c, g, box, px, py, &hit);
        const std::optional<BoxFace> got = PickBoxFace(c, g, box, px, py, kCutW, kCutH);
        ASSERT_EQ(got.has_value(), want.has_value()) << azimuth << " " << px << "," << py;
        if (!got) {
          ++misses;
          continue;
        }
        ++hits;
        EXPECT_EQ(got->axis, want->axis);
        EXPECT_EQ(got->high, want->high);
        // The face point under the pixel projects onto the pixel's centre.
        const auto q = c.camera().Project(g.WorldToPhysical(hit), kCutW, kCutH);
        ASSERT_TRUE(q.has_value());
        EXPECT_NEAR(q->x, px + 0.5, 1e-6);
        EXPECT_NEAR(q->y, py + 0.5, 1e-6);
      }
    }
  }
  EXPECT_GT(hits, 100);
  EXPECT_GT(misses, 100);
  ViewCamera c(g);
  EXPECT_FALSE(PickBoxFace(c, g, box, -1, 0, kCutW, kCutH).has_value());  // not a frame pixel
}

TEST(CropBoxDrag, MovingAFaceKeepsItInsideTheLimitsAndOffTheOppositeFace) {
  const WorldBox limits{{0, 0, 0}, {100, 80, 60}};
  const WorldBox start{{10, 10, 10}, {90, 70, 50}};
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {0, true}, -15.0, limits).hi.x, 75.0);
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {0, true}, -15.0, limits).lo.x, 10.0);
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {1, false}, 25.0, limits).lo.y, 35.0);
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {2, true}, 40.0, limits).hi.z, 60.0);    // the limit
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {2, false}, -40.0, limits).lo.z, 0.0);   // the limit
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {0, false}, 500.0, limits, 2.0).lo.x, 88.0);  // the gap
  EXPECT_DOUBLE_EQ(MoveBoxFace(start, {0, true}, -500.0, limits, 2.0).hi.x, 12.0);
}

TEST(CropBoxDrag, AFaceFollowsTheMouseAlongItsImageOnScreen) {
  const VolumeGeometry g = Rotated();
  int followed = 0;
  for (double azimuth : {20.0, 110.0, 200.0}) {
    ViewCamera c(g);
    c.Orbit(azimuth / -kOrbitDegPerPixel, 20.0);
    const glm::dvec3 target = c.camera().Target();  // physical, at the orbit centre's depth
    for (int axis = 0; axis < 3; ++axis) {
      glm::dvec3 world_axis(0.0);
      world_axis[axis] = 1.0;
      const glm::dvec3 n = glm::transpose(g.direction) * world_axis;  // physical
      const auto p0 = c.camera().Project(target, kCutW, kCutH);
      const auto p1 = c.camera().Project(target + n, kCutW, kCutH);
      ASSERT_TRUE(p0 && p1);
      const glm::dvec2 image = glm::dvec2(*p1) - glm::dvec2(*p0);  // pixels per mm
      if (glm::length(image) < 0.5 / c.MmPerPixel(kCutW, kCutH)) continue;  // nearly along the view
      // 3 pixels along the face's image, plus 2 across it (ignored).
      const glm::dvec2 along = glm::normalize(image), across{-along.y, along.x};
      const glm::dvec2 mouse = 3.0 * along + 2.0 * across;
      const double t = FaceDragMm(c, g, {axis, true}, mouse.x, mouse.y, kCutW, kCutH);
      const auto moved = c.camera().Project(target + t * n, kCutW, kCutH);
      ASSERT_TRUE(moved);
      const glm::dvec2 d = glm::dvec2(*moved) - glm::dvec2(*p0);
      EXPECT_NEAR(glm::dot(d, along), 3.0, 0.05) << azimuth << " axis " << axis;
      ++followed;
    }
  }
  EXPECT_GE(followed, 6);
}

TEST(CropBoxDrag, AFaceAlongTheViewMovesAwayWhenDraggedUp) {
  const VolumeGeometry g = Rotated();
  ViewCamera c(g);
  // The world axis closest to the view direction.
  const glm::dvec3 forward_world = g.direction * c.camera().Forward();
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(forward_world[a]) > std::abs(forward_world[axis])) axis = a;
  }
  ASSERT_GT(std::abs(forward_world[axis]), 0.98);  // the default view looks along an axis
  const double t = FaceDragMm(c, g, {axis, false}, 0.0, -10.0, kCutW, kCutH);
  EXPECT_NEAR(std::abs(t), 10.0 * c.MmPerPixel(kCutW, kCutH), 1e-9);
  EXPECT_GT(t * forward_world[axis], 0.0);  // away from the viewer
}

TEST(CropBoxDrag, OutlineHasTwelveProjectedEdgesAndFourOnTheHighlightedFace) {
  const VolumeGeometry g = Rotated();
  ViewCamera c(g);
  c.Orbit(30, 15);
  const WorldBox box = VolumeWorldBox(g);
  const std::vector<ScreenSegment> lines = BoxOutline(c, g, box, BoxFace{1, true}, kCutW, kCutH);
  ASSERT_EQ(lines.size(), 12u);
  int on_face = 0;
  for (const ScreenSegment& l : lines) on_face += l.on_face;
  EXPECT_EQ(on_face, 4);
  // The first edge runs from the (lo, lo, lo) corner along world x.
  const auto a = c.camera().Project(g.WorldToPhysical(box.lo), kCutW, kCutH);
  const auto b = c.camera().Project(g.WorldToPhysical({box.hi.x, box.lo.y, box.lo.z}), kCutW, kCutH);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(lines[0].a.x, a->x, 1e-9);
  EXPECT_NEAR(lines[0].b.y, b->y, 1e-9);
  EXPECT_FALSE(lines[0].on_face);  // y = lo: not on the y-high face
  EXPECT_TRUE(BoxOutline(c, g, box, std::nullopt, kCutW, kCutH)[0].on_face == false);
}

TEST(ClipPlaneDrag, FacingPlanePassesThroughTheTargetAndCutsTheEyeSide) {
  const VolumeGeometry g = Rotated();
  ViewCamera c(g);
  c.Orbit(50, -20);
  const v3::ClipPlane plane = ClipPlaneFacingCamera(c, g);
  const glm::dvec3 n{plane.normal().x(), plane.normal().y(), plane.normal().z()};
  EXPECT_NEAR(glm::length(n), 1.0, 1e-12);
  const glm::dvec3 forward_world = g.direction * c.camera().Forward();
  EXPECT_NEAR(glm::dot(n, forward_world), 1.0, 1e-12);
  EXPECT_NEAR(glm::dot(n, g.PhysicalToWorld(c.camera().Target())), plane.offset_mm(), 1e-9);
  EXPECT_LT(glm::dot(n, g.PhysicalToWorld(c.camera().Eye())), plane.offset_mm());  // cut away
}

TEST(ClipPlaneDrag, MovingKeepsThePlaneOnTheBoxAndNormalisesTheNormal) {
  const WorldBox box{{0, 0, 0}, {100, 80, 60}};
  v3::ClipPlane plane;
  plane.mutable_normal()->set_z(2.0);  // keeps 2 z >= 20: z >= 10
  plane.set_offset_mm(20.0);
  const v3::ClipPlane moved = MoveClipPlane(plane, 5.0, box);
  EXPECT_DOUBLE_EQ(moved.normal().z(), 1.0);
  EXPECT_DOUBLE_EQ(moved.offset_mm(), 15.0);
  EXPECT_DOUBLE_EQ(MoveClipPlane(plane, 500.0, box).offset_mm(), 60.0);
  EXPECT_DOUBLE_EQ(MoveClipPlane(plane, -500.0, box).offset_mm(), 0.0);
}

TEST(ClipPlaneDrag, DraggingUpCutsDeeperIntoAPlaneFacingTheCamera) {
  const VolumeGeometry g = Rotated();
  ViewCamera c(g);
  c.Orbit(-30, 10);
  const v3::ClipPlane plane = ClipPlaneFacingCamera(c, g);
  const double mm = c.MmPerPixel(kCutW, kCutH);
  EXPECT_NEAR(ClipDragMm(c, g, plane, 3.0, -10.0, kCutW, kCutH), 10.0 * mm, 1e-9);
  EXPECT_NEAR(ClipDragMm(c, g, plane, 0.0, 4.0, kCutW, kCutH), -4.0 * mm, 1e-9);
}

}  // namespace
}  // namespace vpm::view

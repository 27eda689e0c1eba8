// Camera conventions: anterior default view, head up, patient's left on the
// right, whole box in view; orbit, pan, zoom, reset; mirrored directions.
#include <cmath>

#include <gtest/gtest.h>

#include "server/raycast/camera.h"

namespace vpm {
namespace {

VolumeGeometry Box(glm::dvec3 spacing = {1.5, 1.5, 0.9}) {
  VolumeGeometry g;
  g.dims = {256, 200, 160};
  g.spacing_mm = spacing;
  return g;
}

void ExpectNear(const glm::dvec3& a, const glm::dvec3& b, double tol = 1e-9) {
  EXPECT_NEAR(a.x, b.x, tol);
  EXPECT_NEAR(a.y, b.y, tol);
  EXPECT_NEAR(a.z, b.z, tol);
}

TEST(Camera, DefaultIsAnteriorHeadUpLeftOnTheRight) {
  const VolumeGeometry g = Box();
  const Camera cam = Camera::ForVolume(g);
  ExpectNear(cam.Forward(), {0, 1, 0});  // looking posterior
  ExpectNear(cam.Up(), {0, 0, 1});       // superior up
  ExpectNear(cam.Right(), {1, 0, 0});    // patient's left on the image right
  EXPECT_LT(cam.Eye().y, 0.0);           // in front of the box
  const glm::dvec3 c = 0.5 * g.extent_mm();
  const auto centre = *cam.Project(c, 200, 100);
  EXPECT_NEAR(centre.x, 100.0, 1e-9);
  EXPECT_NEAR(centre.y, 50.0, 1e-9);
  const auto left = *cam.Project(c + glm::dvec3(50, 0, 0), 200, 100);
  const auto head = *cam.Project(c + glm::dvec3(0, 0, 50), 200, 100);
  EXPECT_GT(left.x, centre.x);
  EXPECT_LT(head.y, centre.y);
}

TEST(Camera, WholeBoxInViewForAnyAspect) {
  for (const glm::dvec3 spacing : {glm::dvec3(1.5, 1.5, 0.9), glm::dvec3(1e-3, 2e-3, 1e-3),
                                   glm::dvec3(1e3, 1e3, 5e3)}) {
    const VolumeGeometry g = Box(spacing);
    for (auto [w, h] : {std::pair{512, 512}, {640, 200}, {120, 400}}) {
      const Camera cam = Camera::ForVolume(g);
      const glm::dvec3 e = g.extent_mm();
      for (int c = 0; c < 8; ++c) {
        const glm::dvec3 corner((c & 1) ? e.x : 0, (c & 2) ? e.y : 0, (c & 4) ? e.z : 0);
        const auto p = cam.Project(corner, w, h);
        ASSERT_TRUE(p.has_value());
        EXPECT_GE(p->x, 0.0);
        EXPECT_LE(p->x, w);
        EXPECT_GE(p->y, 0.0);
        EXPECT_LE(p->y, h);
      }
    }
  }
}

TEST(Camera, OrbitPanZoomReset) {
  const VolumeGeometry g = Box();
  Camera cam = Camera::ForVolume(g);
  const Camera::Pose home = cam.pose();
  cam.Orbit(90.0, 0.0);  // left lateral: camera at the patient's left, looking right (-x)
  ExpectNear(cam.Forward(), {-1, 0, 0});
  ExpectNear(cam.Up(), {0, 0, 1});
  cam.Orbit(90.0, 0.0);  // posterior view: left and right swap
  ExpectNear(cam.Forward(), {0, -1, 0});
  ExpectNear(cam.Right(), {-1, 0, 0});
  cam.Reset();
  // Tilting over the head, looking down: up keeps turning with the camera,
  // so the posterior side is at the top, as a turntable orbit goes.
  cam.Orbit(0.0, 90.0);
  ExpectNear(cam.Forward(), {0, 0, -1});
  ExpectNear(cam.Up(), {0, 1, 0});
  cam.Reset();
  const glm::dvec3 eye0 = cam.Eye();
  cam.Pan(10.0, -5.0);
  ExpectNear(cam.Eye() - eye0, {10.0, 0.0, -5.0});
  ExpectNear(cam.Forward(), {0, 1, 0});
  cam.Zoom(2.0);
  EXPECT_DOUBLE_EQ(cam.pose().distance_mm, home.distance_mm / 2.0);
  cam.Reset();
  EXPECT_EQ(cam.pose().distance_mm, home.distance_mm);
  EXPECT_EQ(cam.pose().pan_mm, home.pan_mm);
  EXPECT_TRUE(cam.Validate().ok());
}

TEST(Camera, RaysAndProjectionAgree) {
  Camera cam = Camera::ForVolume(Box());
  cam.Orbit(37.0, -21.0);
  cam.Pan(3.0, 4.0);
  const CameraRays rays = cam.Rays(320, 200);
  for (auto [px, py] : {std::pair{0, 0}, {319, 199}, {160, 50}, {17, 180}}) {
    const glm::dvec3 p = rays.eye_mm + 500.0 * rays.Direction(px, py);
    const auto q = *cam.Project(p, 320, 200);
    EXPECT_NEAR(q.x, px + 0.5, 1e-6);
    EXPECT_NEAR(q.y, py + 0.5, 1e-6);
  }
}

TEST(Camera, AnatomicalViewFollowsTheDirectionMatrix) {
  // Index axes stored as (z, x, y) of LPS, and one mirrored: the anterior
  // view must still look posterior with the head up and left on the right.
  VolumeGeometry g = Box();
  g.direction = glm::dmat3(glm::dvec3(0, 0, 1), glm::dvec3(-1, 0, 0), glm::dvec3(0, 1, 0));
  const Camera cam = Camera::ForVolume(g);
  const glm::dvec3 world_forward = g.direction * cam.Forward();
  const glm::dvec3 world_up = g.direction * cam.Up();
  const glm::dvec3 world_right = g.direction * cam.Right();
  ExpectNear(world_forward, {0, 1, 0});
  ExpectNear(world_up, {0, 0, 1});
  ExpectNear(world_right, {1, 0, 0});
}

TEST(Camera, RejectsNonFiniteAndDegeneratePoses) {
  Camera cam = Camera::ForVolume(Box());
  Camera::Pose p = cam.pose();
  p.pan_mm.x = INFINITY;
  cam.set_pose(p);
  EXPECT_EQ(cam.Validate().code(), absl::StatusCode::kInvalidArgument);
  p = Camera::ForVolume(Box()).pose();
  p.fov_deg = 179.0;
  cam.set_pose(p);
  EXPECT_EQ(cam.Validate().code(), absl::StatusCode::kInvalidArgument);
  p.fov_deg = 30.0;
  p.distance_mm = -1.0;
  cam.set_pose(p);
  EXPECT_EQ(cam.Validate().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

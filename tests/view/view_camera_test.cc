// The viewer's camera math against the server's camera class: what a pick
// grabs, how far a drag pulls, and what orbit, zoom and pan do.
#include <gtest/gtest.h>

#include "client/view/view_camera.h"

namespace vpm::view {
namespace {

// The 128^3 abdomen phantom's geometry (spacing from `vpm volume info`).
VolumeGeometry Phantom() {
  VolumeGeometry g;
  g.dims = {128, 128, 128};
  g.spacing_mm = {2.96875, 2.96875, 1.875};
  return g;
}

constexpr int kW = 256, kH = 192;  // a non-square frame, pixels

glm::dvec2 ProjectXY(const ViewCamera& c, const glm::dvec3& p) {
  auto q = c.camera().Project(p, kW, kH);
  EXPECT_TRUE(q.has_value());
  return q ? glm::dvec2(q->x, q->y) : glm::dvec2(0.0);
}

TEST(ViewCamera, PickPointLiesOnThePixelRayInTheOrbitCentrePlane) {
  ViewCamera c(Phantom());
  c.Orbit(30, -10);
  auto p = c.PickPoint(140, 90, kW, kH);
  ASSERT_TRUE(p.has_value());
  const glm::dvec2 xy = ProjectXY(c, *p);
  EXPECT_NEAR(xy.x, 140.5, 1e-6);  // the pixel's centre
  EXPECT_NEAR(xy.y, 90.5, 1e-6);
  const double depth = glm::dot(*p - c.camera().Eye(), c.camera().Forward());
  EXPECT_NEAR(depth, c.camera().pose().distance_mm, 1e-6);
}

TEST(ViewCamera, PickOutsideTheVolumeBoxIsEmpty) {
  ViewCamera c(Phantom());
  EXPECT_TRUE(c.PickPoint(kW / 2, kH / 2, kW, kH).has_value());
  EXPECT_FALSE(c.PickPoint(0, 0, kW, kH).has_value());   // the plane's corner is outside
  EXPECT_FALSE(c.PickPoint(-1, 5, kW, kH).has_value());  // not a pixel of the frame
  EXPECT_FALSE(c.PickPoint(5, kH, kW, kH).has_value());
}

TEST(ViewCamera, DragOffsetMovesTheGrabbedPointWithTheMouse) {
  for (double azimuth : {0.0, 70.0, 200.0}) {
    ViewCamera c(Phantom());
    c.Orbit(azimuth / -kOrbitDegPerPixel, 25.0);
    const auto p = c.PickPoint(120, 100, kW, kH);
    ASSERT_TRUE(p.has_value());
    const glm::dvec3 offset = c.DragOffsetMm(17.0, -9.0, kW, kH);
    const glm::dvec2 before = ProjectXY(c, *p), after = ProjectXY(c, *p + offset);
    EXPECT_NEAR(after.x - before.x, 17.0, 1e-6) << azimuth;
    EXPECT_NEAR(after.y - before.y, -9.0, 1e-6) << azimuth;
    // In the plane facing the camera: no motion in depth.
    EXPECT_NEAR(glm::dot(offset, c.camera().Forward()), 0.0, 1e-9);
  }
}

TEST(ViewCamera, DragScaleIsFieldOfViewOverShorterSide) {
  ViewCamera c(Phantom());
  const double d = c.camera().pose().distance_mm;
  const double expected = 2.0 * d * std::tan(15.0 * 3.14159265358979323846 / 180.0) / kH;
  EXPECT_NEAR(c.MmPerPixel(kW, kH), expected, 1e-9);
  EXPECT_NEAR(glm::length(c.DragOffsetMm(10, 0, kW, kH)), 10 * expected, 1e-9);
}

TEST(ViewCamera, OrbitTurnsByDegreesPerPixel) {
  ViewCamera c(Phantom());
  c.Orbit(10, -5);
  EXPECT_NEAR(c.ToProto().azimuth_deg(), -10 * kOrbitDegPerPixel, 1e-12);
  EXPECT_NEAR(c.ToProto().elevation_deg(), -5 * kOrbitDegPerPixel, 1e-12);
}

TEST(ViewCamera, WheelUpZoomsInAndDownZoomsOut) {
  ViewCamera c(Phantom());
  const double d0 = c.ToProto().distance_mm();
  c.Zoom(2);
  EXPECT_NEAR(c.ToProto().distance_mm(), d0 / (kZoomPerWheelClick * kZoomPerWheelClick), 1e-9);
  c.Zoom(-2);
  EXPECT_NEAR(c.ToProto().distance_mm(), d0, 1e-9);
}

TEST(ViewCamera, PanMovesThePictureWithTheMouse) {
  ViewCamera c(Phantom());
  const glm::dvec3 centre = 0.5 * Phantom().extent_mm();
  const glm::dvec2 before = ProjectXY(c, centre);
  c.Pan(12, -7, kW, kH);
  const glm::dvec2 after = ProjectXY(c, centre);
  EXPECT_NEAR(after.x - before.x, 12, 1e-6);
  EXPECT_NEAR(after.y - before.y, -7, 1e-6);
}

TEST(ViewCamera, ResetReturnsToTheFittedView) {
  ViewCamera c(Phantom());
  const v3::Camera home = c.ToProto();
  c.Orbit(50, 20);
  c.Zoom(3);
  c.Pan(5, 5, kW, kH);
  c.Reset();
  EXPECT_EQ(c.ToProto().SerializeAsString(), home.SerializeAsString());
  EXPECT_GT(home.distance_mm(), 0);  // explicit, so the server needs no fit of its own
}

TEST(GeometryFromProto, ReadsDirectionColumnMajor) {
  v3::VolumeInfo info;
  for (int n : {10, 20, 30}) info.add_dims(n);
  info.mutable_spacing_mm()->set_x(1);
  info.mutable_spacing_mm()->set_y(2);
  info.mutable_spacing_mm()->set_z(3);
  // Axis i along world -x, j along +y, k along +z.
  for (double v : {-1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0}) info.add_direction(v);
  auto g = GeometryFromProto(info);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_EQ(g->dims[2], 30);
  EXPECT_EQ(g->direction[0][0], -1.0);  // column 0 = axis i
  EXPECT_EQ(g->spacing_mm.z, 3.0);
}

TEST(GeometryFromProto, RefusesMissingDimsAndZeroSpacing) {
  v3::VolumeInfo info;
  EXPECT_FALSE(GeometryFromProto(info).ok());
  for (int n : {10, 20, 30}) info.add_dims(n);
  EXPECT_FALSE(GeometryFromProto(info).ok());  // spacing 0
}

}  // namespace
}  // namespace vpm::view

// The clip region's geometry on the CPU: its checks, the move from world to
// physical space, the ray interval and the pick through a cut. The GPU
// against the CPU reference with clipping: raycast_test.cc (CropAndClip_*).
#include <cmath>

#include <gtest/gtest.h>

#include "server/raycast/clip_region.h"
#include "server/raycast/pick_ray.h"
#include "tests/raycast/render_test_util.h"

namespace vpm {
namespace {

bool Keeps(const std::vector<glm::dvec4>& planes, const glm::dvec3& p) {
  for (const glm::dvec4& plane : planes) {
    if (glm::dot(glm::dvec3(plane), p) < plane.w - 1e-9) return false;
  }
  return true;
}

TEST(ClipRegion, ValidateRefusesBadRegions) {
  ClipRegion ok;
  ok.crop = CropBox{glm::dvec3(0.0), glm::dvec3(1.0)};
  ok.planes.push_back(ClipPlane{glm::dvec3(0.0, 0.0, 2.0), 3.0});
  EXPECT_TRUE(ValidateClipRegion(ok).ok());
  ClipRegion r = ok;
  r.crop->lo_mm.y = 2.0;
  EXPECT_EQ(ValidateClipRegion(r).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(ValidateClipRegion(r).message().find("y from 2"), std::string::npos);
  r = ok;
  r.crop->hi_mm.x = NAN;
  EXPECT_FALSE(ValidateClipRegion(r).ok());
  r = ok;
  r.planes[0].normal = glm::dvec3(0.0);
  EXPECT_FALSE(ValidateClipRegion(r).ok());
  r = ok;
  r.planes[0].offset_mm = INFINITY;
  EXPECT_FALSE(ValidateClipRegion(r).ok());
  r = ok;  // 6 (box) + 10 planes fit, 11 do not
  r.planes.assign(kMaxClipPlanes - 6, ClipPlane{});
  EXPECT_TRUE(ValidateClipRegion(r).ok());
  r.planes.push_back(ClipPlane{});
  EXPECT_FALSE(ValidateClipRegion(r).ok());
}

// A volume with an oblique direction, a mirror and an origin: a world point
// is kept exactly when its physical position satisfies the moved planes.
TEST(ClipRegion, PlanesFollowTheVolumeFrame) {
  VolumeGeometry g;
  g.dims = {10, 10, 10};
  g.spacing_mm = {0.7, 1.0, 2.5};
  g.origin_mm = {-120.0, 35.0, 800.0};
  const double a = 0.4;
  g.direction = glm::dmat3(glm::dvec3(std::cos(a), std::sin(a), 0.0),
                           glm::dvec3(-std::sin(a), std::cos(a), 0.0), glm::dvec3(0.0, 0.0, -1.0));
  ClipRegion region;
  region.crop = CropBox{glm::dvec3(-125.0, 30.0, 790.0), glm::dvec3(-110.0, 45.0, 805.0)};
  region.planes.push_back(ClipPlane{glm::dvec3(2.0, -1.0, 0.5), -300.0});
  const std::vector<glm::dvec4> planes = ClipPlanesInPhysical(region, g);
  ASSERT_EQ(planes.size(), 7u);
  int kept = 0, cut = 0;
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 w(-130.0 + 25.0 * std::fmod(i * 0.6180339, 1.0),
                       25.0 + 25.0 * std::fmod(i * 0.4142135, 1.0),
                       785.0 + 25.0 * std::fmod(i * 0.7320508, 1.0));
    const bool in_box = glm::all(glm::greaterThanEqual(w, region.crop->lo_mm)) &&
                        glm::all(glm::lessThanEqual(w, region.crop->hi_mm));
    const bool in_plane = glm::dot(region.planes[0].normal, w) >= region.planes[0].offset_mm;
    const bool expected = in_box && in_plane;
    EXPECT_EQ(Keeps(planes, g.WorldToPhysical(w)), expected) << i;
    (expected ? kept : cut) += 1;
  }
  EXPECT_GT(kept, 100);  // the test saw both sides
  EXPECT_GT(cut, 100);
}

TEST(ClipRegion, RayIntervalNarrowsToTheKeptSide) {
  const std::vector<glm::vec4> planes = {glm::vec4(1.0f, 0.0f, 0.0f, 3.0f),    // x >= 3
                                         glm::vec4(-1.0f, 0.0f, 0.0f, -8.0f)};  // x <= 8
  float t_near = 0.0f, t_far = 20.0f;
  ClipRayInterval(planes, glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f), t_near, t_far);
  EXPECT_FLOAT_EQ(t_near, 3.0f);
  EXPECT_FLOAT_EQ(t_far, 8.0f);
  // A ray parallel to a plane, on its cut side: nothing left.
  t_near = 0.0f;
  t_far = 20.0f;
  ClipRayInterval(planes, glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f), t_near, t_far);
  EXPECT_GT(t_near, t_far);
}

TEST(ClipRegion, CutPlaneFacingKeepsWhatLiesBeyondThePoint) {
  const ClipPlane plane = CutPlaneFacing(glm::dvec3(1.0, 2.0, 3.0), glm::dvec3(0.0, 5.0, 0.0));
  EXPECT_NEAR(glm::length(plane.normal), 1.0, 1e-12);
  EXPECT_GE(glm::dot(plane.normal, glm::dvec3(1.0, 2.5, 3.0)), plane.offset_mm);
  EXPECT_LT(glm::dot(plane.normal, glm::dvec3(1.0, 1.5, 3.0)), plane.offset_mm);
}

// A pick through a cut lands on the cut face when tissue is there, not on
// the surface in front of it.
TEST(ClipRegion, PickLandsOnTheCutFace) {
  const Volume volume = testing::MakeSphereRodVolume();
  const glm::dvec3 c = 0.5 * volume.geometry().extent_mm();
  const RenderPreset preset = *MakeRenderPreset("ct-soft-tissue", volume);
  const glm::dvec3 eye(c.x, -200.0, c.z);
  const glm::dvec3 dir(0.0, 1.0, 0.0);
  const auto surface = PickAlongRay(volume, preset, RenderMode::kDvr, eye, dir);
  ASSERT_TRUE(surface.has_value());
  const double cut_y = c.y - 3.0;
  ASSERT_LT(surface->y, cut_y - 2.0);  // the slab's front face lies before the cut
  const std::vector<glm::dvec4> planes = {glm::dvec4(0.0, 1.0, 0.0, cut_y)};
  const auto cut = PickAlongRay(volume, preset, RenderMode::kDvr, eye, dir, planes);
  ASSERT_TRUE(cut.has_value());
  EXPECT_GE(cut->y, cut_y);
  EXPECT_LT(cut->y, cut_y + 2.0);
}

}  // namespace
}  // namespace vpm

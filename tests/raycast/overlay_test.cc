// Overlays: deformable vertices yellow, hard ones blue, handles red, the
// drag arrow green, all at the camera's projection of their positions.
#include <gtest/gtest.h>

#include "server/raycast/overlay.h"

namespace vpm {
namespace {

VolumeGeometry OverlayBox() {
  VolumeGeometry g;
  g.dims = {101, 101, 101};
  g.spacing_mm = {1.0, 1.0, 1.0};
  return g;
}

bool PixelIs(const std::vector<uint8_t>& rgba, int w, glm::dvec3 at, const uint8_t* rgb) {
  const uint8_t* p = &rgba[(size_t(at.y) * w + size_t(at.x)) * 4];
  return p[0] == rgb[0] && p[1] == rgb[1] && p[2] == rgb[2];
}

TEST(Overlay, DrawsMeshVerticesByKindAndTheDrag) {
  ProxyMesh mesh;
  mesh.vertices.resize(4);
  mesh.vertices[0].position_mm = {30, 50, 50};                              // deformable
  mesh.vertices[1].position_mm = {70, 50, 50};
  mesh.vertices[1].hard = true;                                            // hard
  mesh.vertices[2].position_mm = {50, 50, 80};                             // handle
  mesh.vertices[3].position_mm = {50, 50, 20};
  mesh.vertices[3].kind = VertexKind::kRefined;                             // refined
  const int32_t handles[] = {2};
  OverlayData overlay = MakeMeshOverlay(mesh, {}, handles);
  overlay.drag = DragArrow{{50, 50, 50}, {50, 50, 35}};
  overlay.point_radius_px = 5.0;  // centre pixels fully covered, no edge blending
  const int w = 200, h = 200;
  std::vector<uint8_t> rgba(size_t(w) * h * 4, 0);
  const Camera cam = Camera::ForVolume(OverlayBox());
  DrawOverlay(overlay, cam, w, h, rgba);
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({30, 50, 50}, w, h), kDeformableRgb));
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({70, 50, 50}, w, h), kHardRgb));
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({50, 50, 80}, w, h), kHandleRgb));
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({50, 50, 20}, w, h), kDeformableRgb));
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({50, 50, 42}, w, h), kDragRgb));
  // Nothing far from every mark.
  EXPECT_EQ(rgba[(size_t(5) * w + 5) * 4], 0);

  // Deformed positions move the discs.
  const std::vector<glm::dvec3> moved = {{30, 50, 60}, {70, 50, 50}, {50, 50, 80}, {50, 50, 20}};
  std::fill(rgba.begin(), rgba.end(), 0);
  OverlayData moved_overlay = MakeMeshOverlay(mesh, moved);
  moved_overlay.point_radius_px = 5.0;
  DrawOverlay(moved_overlay, cam, w, h, rgba);
  EXPECT_TRUE(PixelIs(rgba, w, *cam.Project({30, 50, 60}, w, h), kDeformableRgb));
  EXPECT_FALSE(PixelIs(rgba, w, *cam.Project({30, 50, 50}, w, h), kDeformableRgb));
}

}  // namespace
}  // namespace vpm

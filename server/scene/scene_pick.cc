// DeformableScene::Pick: the point a pixel of a frame shows, for a grab or
// a pin by pixel (docs/SERVICE.md, "Picking").
#include <cmath>

#include "server/raycast/pick_ray.h"
#include "server/scene/deformable_scene.h"

namespace vpm {
namespace {

bool InsideBox(const VolumeGeometry& geometry, const glm::dvec3& p_mm) {
  const glm::dvec3 extent = geometry.extent_mm();
  for (int axis = 0; axis < 3; ++axis) {
    if (!(p_mm[axis] >= 0.0 && p_mm[axis] <= extent[axis])) return false;
  }
  return true;
}

}  // namespace

Result<glm::dvec3> DeformableScene::Pick(const SceneView& view, int pixel_x, int pixel_y) const {
  if (pixel_x < 0 || pixel_x >= view.width || pixel_y < 0 || pixel_y >= view.height) {
    return absl::OutOfRangeError(StrCat("pixel (", pixel_x, ", ", pixel_y,
                                        ") is outside the frame, ", view.width, "x",
                                        view.height));
  }
  const CameraRays rays = view.camera.Rays(view.width, view.height);
  const glm::dvec3 dir = rays.Direction(pixel_x, pixel_y);
  // A view that never had a frame has no preset to pick with: the plane only.
  if (view.preset.points.size() >= 2) {
    const std::vector<glm::dvec4> clip =
        ClipPlanesInPhysical(ViewClip(view), volume_->geometry());
    if (auto hit = PickAlongRay(*volume_, view.preset, view.mode, rays.eye_mm, dir, clip)) {
      return *hit;
    }
  }
  // Nothing shown along the ray: the plane through the orbit centre that
  // faces the camera.
  const Camera& camera = view.camera;
  const double t = glm::dot(camera.Target() - rays.eye_mm, camera.Forward()) /
                   glm::dot(dir, camera.Forward());
  const glm::dvec3 p = rays.eye_mm + t * dir;
  if (!std::isfinite(t) || !InsideBox(volume_->geometry(), p)) {
    return absl::OutOfRangeError(StrCat("pixel (", pixel_x, ", ", pixel_y,
                                        ") shows no tissue and its ray meets the plane through "
                                        "the orbit centre outside the volume"));
  }
  return p;
}

}  // namespace vpm

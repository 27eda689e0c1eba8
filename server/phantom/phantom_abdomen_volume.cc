// The abdomen phantom as a Volume: geometry, landmarks, rasterization.
#include <utility>

#include "server/phantom/phantom_abdomen.h"

namespace vpm::phantom {

VolumeGeometry AbdomenGeometry(const PhantomSpec& spec) {
  VolumeGeometry g;
  g.dims = spec.dims;
  const glm::dvec3 n(static_cast<double>(spec.dims[0]), static_cast<double>(spec.dims[1]),
                     static_cast<double>(spec.dims[2]));
  g.spacing_mm = spec.spacing_mm.value_or(kAbdomenFieldOfViewMm / n);
  // Voxel (0, 0, 0) sits at world -field of view / 2, so a landmark's
  // physical voxel position (world + field of view / 2) does not depend on
  // dims for the default spacing; the box spans [-fov/2, fov/2 - spacing].
  g.origin_mm = -0.5 * n * g.spacing_mm;
  g.direction = glm::dmat3(1.0);
  return g;
}

std::vector<Landmark> AbdomenLandmarks(const AbdomenAnatomy& a, const VolumeGeometry& g) {
  const std::pair<const char*, std::pair<glm::dvec3, const char*>> kPoints[] = {
      {"left_renal_artery",
       {a.left_renal_artery_mm,
        "left renal artery centreline, halfway between the aorta wall and the hilum"}},
      {"right_renal_artery",
       {a.right_renal_artery_mm,
        "right renal artery centreline (behind the IVC), halfway between aorta wall and hilum"}},
      {"left_kidney_surface",
       {a.left_kidney.lateral_surface_mm,
        "lateral surface of the left kidney (cortex inside, perirenal fat outside)"}},
      {"left_kidney_center", {a.left_kidney.center_mm, "centre of the left kidney (medulla)"}},
      {"right_kidney_center", {a.right_kidney.center_mm, "centre of the right kidney (medulla)"}},
      {"vertebral_body",
       {a.vertebral_body_mm, "centre of the L2 vertebral body (cancellous bone), kidney level"}},
      {"aorta",
       {a.aorta_at_renal_mm, "abdominal aorta centreline at the left renal artery origin"}},
      {"liver", {a.liver_mm, "inside the right liver lobe, away from vessels"}},
      {"spleen", {a.spleen_mm, "centre of the spleen"}},
  };
  std::vector<Landmark> landmarks;
  for (const auto& [name, point] : kPoints) {
    landmarks.push_back({name, g.WorldToPhysical(point.first), point.second});
  }
  return landmarks;
}

Result<Volume> MakeAbdomenPhantom(const PhantomSpec& spec, const VolumeLimits& limits) {
  const VolumeGeometry geometry = AbdomenGeometry(spec);
  RETURN_IF_ERROR(ValidateGeometry(geometry, limits));
  const AbdomenAnatomy anatomy = MakeAbdomenAnatomy();
  const Scene scene = MakeAbdomenScene(anatomy);
  std::vector<float> values(static_cast<size_t>(geometry.voxel_count()));
  RasterOptions options;
  options.noise_seed = spec.seed;
  options.noise_sigma_hu = static_cast<float>(spec.noise_sigma_hu);
  options.threads = spec.threads;
  Rasterize(scene, geometry, options, values);
  ASSIGN_OR_RETURN(Volume volume, Volume::Create(geometry, std::move(values), limits));
  volume.set_landmarks(AbdomenLandmarks(anatomy, geometry));
  return volume;
}

}  // namespace vpm::phantom

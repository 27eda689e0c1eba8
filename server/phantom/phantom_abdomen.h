// The "abdomen" phantom: a deterministic synthetic contrast-enhanced
// (portal-venous-like) abdominal CT, values in HU.
//
// All anatomy is defined in world LPS millimetres (x: patient left, y:
// posterior, z: superior), with world (0, 0, 0) at the centre of the body at
// the level of the second lumbar vertebra, so any dims and spacing show the
// same anatomy. The volume has identity direction and its first voxel at
// world -(dims * spacing) / 2. docs/PHANTOM.md has the anatomy table.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/phantom/phantom.h"
#include "server/phantom/phantom_raster.h"
#include "server/phantom/phantom_shapes.h"
#include "server/volume/volume.h"

namespace vpm::phantom {

// Field of view (mm) for the default spacing: spacing = field of view / dims.
// 256^3 voxels gives 1.484 x 1.484 x 0.9375 mm.
inline const glm::dvec3 kAbdomenFieldOfViewMm{380.0, 380.0, 240.0};

// Tissue values, HU.
namespace hu {
inline constexpr float kAir = -1000.0f;
inline constexpr float kSkin = 40.0f;
inline constexpr float kSubcutaneousFat = -100.0f;
inline constexpr float kFat = -90.0f;  // retroperitoneal, perirenal, mesenteric
inline constexpr float kMuscle = 50.0f;
inline constexpr float kBowel = 30.0f;
inline constexpr float kBowelWall = 40.0f;
inline constexpr float kLumenFluid = 10.0f;  // stomach and colon contents
inline constexpr float kLiver = 60.0f;
inline constexpr float kSpleen = 50.0f;
inline constexpr float kKidneyCortex = 160.0f;
inline constexpr float kKidneyMedulla = 60.0f;
inline constexpr float kUrine = 10.0f;  // renal pelvis, ureter
// Enhanced blood. Every vessel stays below the 250 HU bone threshold
// (docs/ALGORITHM.md section 3) by at least 4 noise sigmas, so no vessel voxel is
// mistaken for bone.
inline constexpr float kAorta = 210.0f;
inline constexpr float kArtery = 200.0f;
inline constexpr float kRenalVein = 180.0f;
inline constexpr float kPortalVein = 160.0f;
inline constexpr float kIvc = 150.0f;
inline constexpr float kCorticalBone = 700.0f;
inline constexpr float kCancellousBone = 300.0f;
inline constexpr float kDisc = 80.0f;
inline constexpr float kSpinalCanal = 20.0f;  // cord and CSF
}  // namespace hu

// Cortex thickness of the kidneys and bones, mm.
inline constexpr double kKidneyCortexMm = 6.0;
inline constexpr double kVertebralCortexMm = 1.8;
inline constexpr double kRibCortexMm = 1.5;

struct Vessel {
  std::string name;
  std::vector<TubeNode> centreline;  // world mm, radius mm
  float hu = 0.0f;
};

struct KidneyGeometry {
  glm::dvec3 center_mm{0.0};
  // Columns: toward the hilum (medial and anterior), the short (anteroposterior)
  // axis, the long axis (superior, tilted medially and posteriorly).
  glm::dmat3 frame{1.0};
  glm::dvec3 semi_axes_mm{0.0};   // along the frame's columns
  glm::dvec3 artery_end_mm{0.0};  // where the renal artery ends, in the sinus
  glm::dvec3 vein_end_mm{0.0};
  glm::dvec3 lateral_surface_mm{0.0};  // end of the width axis facing away from the hilum
};

struct AbdomenAnatomy {
  KidneyGeometry left_kidney;
  KidneyGeometry right_kidney;
  std::vector<Vessel> vessels;        // by name: "aorta", "left_renal_artery", ...
  glm::dvec3 vertebral_body_mm{0.0};  // centre of L2, at kidney level
  glm::dvec3 aorta_at_renal_mm{0.0};  // aorta centreline at the left renal artery origin
  // Renal artery centreline points halfway (arc length) between the aorta
  // wall and the artery's end in the renal sinus.
  glm::dvec3 left_renal_artery_mm{0.0};
  glm::dvec3 right_renal_artery_mm{0.0};
  glm::dvec3 liver_mm{0.0};
  glm::dvec3 spleen_mm{0.0};

  // The vessel called `name`, or nullptr.
  const Vessel* FindVessel(std::string_view name) const;
};

AbdomenAnatomy MakeAbdomenAnatomy();

// The scene: body cross-section, bowel texture, organs, vessels, skeleton.
Scene MakeAbdomenScene(const AbdomenAnatomy& anatomy);
// Spine and ribs, appended to the scene (phantom_abdomen_skeleton.cc).
void AddAbdomenSkeleton(Scene& scene);

// Geometry of an abdomen volume: spacing from spec (or field of view / dims),
// origin -(dims * spacing) / 2 (voxel (0,0,0) centre), identity direction.
VolumeGeometry AbdomenGeometry(const PhantomSpec& spec);

// Named landmarks in physical voxel space (mm) of `geometry`.
std::vector<Landmark> AbdomenLandmarks(const AbdomenAnatomy& anatomy,
                                       const VolumeGeometry& geometry);

// The whole phantom: validates the geometry against `limits` first.
Result<Volume> MakeAbdomenPhantom(const PhantomSpec& spec, const VolumeLimits& limits);

}  // namespace vpm::phantom

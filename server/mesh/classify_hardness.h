// Step 3 of docs/ALGORITHM.md: which vertices are non-deformable (bone).
//  1. v is hard if I[voxel(v)] >= bone_threshold.
//  2. One pass over the hard set of rule 1 (not transitive): a deformable u
//     becomes hard if some hard h has |p_u - p_h| < influence_radius and
//     I[voxel(u)] >= influence_threshold.
//  3. Overrides (by vertex index, box or sphere), applied in order, win over
//     both rules.
//  4. Skeleton (docs/MESH.md, "The skeleton"): a rule-1 vertex is on the
//     skeleton when the 26-connected set of voxels >= bone_threshold
//     through its voxel holds at least skeleton_min_volume_mm3; a rule-2
//     vertex when a skeleton vertex within the influence radius made it
//     hard; an override that makes a vertex hard puts it on the skeleton.
//     Only skeleton vertices are fixed in FEM; the other hard ones are stiff
//     and free.
// Rules 1 and 2 are in HU and apply to CT in HU only (IsCtInHu,
// server/volume/ct_in_hu.h): on an MRI no vertex is hard but by an override
// (its intensities say nothing of bone, and bright fat would be fixed), so
// the box faces and the anchors hold the model.
// Anchors are fixed in FEM anyway and are left deformable here.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/mesh/proxy_mesh.h"
#include "server/volume/volume.h"

namespace vpm {

struct HardnessOverride {
  enum class Shape { kIds, kBox, kSphere };
  Shape shape = Shape::kIds;
  bool hard = true;                 // the state to set
  std::vector<int64_t> ids;         // kIds: indices into the mesh's vertex list
  glm::dvec3 box_min_mm{0.0};       // kBox: inclusive corners, physical voxel space
  glm::dvec3 box_max_mm{0.0};
  glm::dvec3 center_mm{0.0};        // kSphere
  double radius_mm = 0.0;           // kSphere: inclusive
};

struct ClassifyParams {
  double bone_threshold = 250.0;      // HU
  double influence_threshold = 100.0; // HU
  double influence_factor = 0.75;     // influence radius = factor * R
  // Bone components smaller than this are islands (stones, calcifications),
  // not skeleton: mm^3. On the abdominal CT of tests/data the rib segments
  // the field of view cuts off are 1,377 mm^3 and more, the kidney stones
  // 351 mm^3 and less (docs/MESH.md). 0: every hard vertex is skeleton.
  double skeleton_min_volume_mm3 = 1000.0;
  std::vector<HardnessOverride> overrides;
};

// Sets vertices[i].hard and .skeleton. R_mm: the density radius of step 2.
Status ClassifyHardness(const Volume& volume, double R_mm, const ClassifyParams& params,
                        std::vector<MeshVertex>& vertices);

}  // namespace vpm

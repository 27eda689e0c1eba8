// Step 3 of docs/ALGORITHM.md: which vertices are non-deformable (bone).
//  1. v is hard if I[voxel(v)] >= bone_threshold.
//  2. One pass over the hard set of rule 1 (not transitive): a deformable u
//     becomes hard if some hard h has |p_u - p_h| < influence_radius and
//     I[voxel(u)] >= influence_threshold.
//  3. Overrides (by vertex index, box or sphere), applied in order, win over
//     both rules.
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
  std::vector<HardnessOverride> overrides;
};

// Sets vertices[i].hard. R_mm: the density radius of step 2.
Status ClassifyHardness(const Volume& volume, double R_mm, const ClassifyParams& params,
                        std::vector<MeshVertex>& vertices);

}  // namespace vpm

#include "server/mesh/classify_hardness.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "server/mesh/point_grid.h"
#include "server/volume/ct_in_hu.h"
#include "server/volume/voxel_flood.h"

namespace vpm {
namespace {

float ValueAt(const Volume& volume, const MeshVertex& v) {
  return volume.At(v.voxel[0], v.voxel[1], v.voxel[2]);
}

Status ApplyOverride(const HardnessOverride& o, std::vector<MeshVertex>& vertices) {
  switch (o.shape) {
    case HardnessOverride::Shape::kIds:
      for (int64_t id : o.ids) {
        if (id < 0 || id >= static_cast<int64_t>(vertices.size())) {
          return absl::NotFoundError(StrCat("hardness override: vertex ", id,
                                            " does not exist (the mesh has ", vertices.size(),
                                            " vertices)"));
        }
        vertices[id].hard = vertices[id].skeleton = o.hard;
      }
      return absl::OkStatus();
    case HardnessOverride::Shape::kBox:
      for (auto& v : vertices) {
        if (glm::all(glm::greaterThanEqual(v.position_mm, o.box_min_mm)) &&
            glm::all(glm::lessThanEqual(v.position_mm, o.box_max_mm))) {
          v.hard = v.skeleton = o.hard;
        }
      }
      return absl::OkStatus();
    case HardnessOverride::Shape::kSphere:
      if (!(o.radius_mm >= 0.0) || !std::isfinite(o.radius_mm)) {
        return absl::InvalidArgumentError("hardness override: sphere radius must be >= 0");
      }
      for (auto& v : vertices) {
        if (PointDistance(v.position_mm, o.center_mm) <= o.radius_mm) {
          v.hard = v.skeleton = o.hard;
        }
      }
      return absl::OkStatus();
  }
  return absl::InvalidArgumentError("hardness override: unknown shape");
}

// Rule 4 for the rule-1 vertices `bone`: sets .skeleton where the bone
// component through the vertex's voxel holds at least min_volume_mm3. Each
// fill stops at that size, and the voxels of every fill are remembered with
// their answer, so a component is filled about once.
void MarkSkeleton(const Volume& volume, double bone_threshold, double min_volume_mm3,
                  const std::vector<int64_t>& bone, std::vector<MeshVertex>& vertices) {
  const glm::dvec3 s = volume.spacing_mm();
  const double voxel_mm3 = s.x * s.y * s.z;
  const auto limit = static_cast<int64_t>(std::ceil(min_volume_mm3 / voxel_mm3));
  std::unordered_map<int64_t, bool> known;  // voxel -> on a large component
  const VoxelPredicate is_bone = [&](int64_t i, int64_t j, int64_t k, int64_t) {
    return volume.At(i, j, k) >= bone_threshold;
  };
  for (int64_t b : bone) {
    MeshVertex& v = vertices[b];
    const int64_t seed = volume.LinearIndex(v.voxel[0], v.voxel[1], v.voxel[2]);
    if (const auto it = known.find(seed); it != known.end()) {
      v.skeleton = it->second;
      continue;
    }
    if (limit <= 1) {
      v.skeleton = true;
      continue;
    }
    const VoxelFlood fill = FloodFill(volume, v.voxel, is_bone, limit, Connectivity::kFull26);
    const bool large = !fill.complete || static_cast<int64_t>(fill.voxels.size()) >= limit;
    for (int64_t voxel : fill.voxels) known[voxel] = large;
    v.skeleton = large;
  }
}

}  // namespace

Status ClassifyHardness(const Volume& volume, double R_mm, const ClassifyParams& params,
                        std::vector<MeshVertex>& vertices) {
  for (double t : {params.bone_threshold, params.influence_threshold, params.influence_factor}) {
    if (!std::isfinite(t)) return absl::InvalidArgumentError("classification thresholds must be finite");
  }
  const bool hu_rules = IsCtInHu(volume);
  std::vector<int64_t> bone;  // hard by rule 1
  for (size_t i = 0; i < vertices.size(); ++i) {
    auto& v = vertices[i];
    v.hard =
        hu_rules && v.kind != VertexKind::kAnchor && ValueAt(volume, v) >= params.bone_threshold;
    v.skeleton = false;
    if (v.hard) bone.push_back(static_cast<int64_t>(i));
  }
  if (!std::isfinite(params.skeleton_min_volume_mm3) || params.skeleton_min_volume_mm3 < 0.0) {
    return absl::InvalidArgumentError("skeleton_min_volume_mm3 must be finite and >= 0");
  }
  MarkSkeleton(volume, params.bone_threshold, params.skeleton_min_volume_mm3, bone, vertices);
  const double radius = params.influence_factor * R_mm;
  std::vector<char> influenced(vertices.size(), 0);  // 1: by bone, 2: by skeleton
  for (size_t i = 0; i < vertices.size(); ++i) {
    const auto& u = vertices[i];
    if (u.hard || u.kind == VertexKind::kAnchor ||
        ValueAt(volume, u) < params.influence_threshold) {
      continue;
    }
    for (int64_t h : bone) {
      if (PointDistance(u.position_mm, vertices[h].position_mm) < radius) {
        influenced[i] = vertices[h].skeleton ? 2 : std::max<char>(influenced[i], 1);
        if (influenced[i] == 2) break;
      }
    }
  }
  // Applied after the scan, so influence never chains (one pass, not transitive).
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (influenced[i]) vertices[i].hard = true;
    if (influenced[i] == 2) vertices[i].skeleton = true;
  }
  for (const auto& o : params.overrides) RETURN_IF_ERROR(ApplyOverride(o, vertices));
  return absl::OkStatus();
}

}  // namespace vpm

#include "server/mesh/classify_hardness.h"

#include <cmath>

#include "server/mesh/point_grid.h"

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
        vertices[id].hard = o.hard;
      }
      return absl::OkStatus();
    case HardnessOverride::Shape::kBox:
      for (auto& v : vertices) {
        if (glm::all(glm::greaterThanEqual(v.position_mm, o.box_min_mm)) &&
            glm::all(glm::lessThanEqual(v.position_mm, o.box_max_mm))) {
          v.hard = o.hard;
        }
      }
      return absl::OkStatus();
    case HardnessOverride::Shape::kSphere:
      if (!(o.radius_mm >= 0.0) || !std::isfinite(o.radius_mm)) {
        return absl::InvalidArgumentError("hardness override: sphere radius must be >= 0");
      }
      for (auto& v : vertices) {
        if (PointDistance(v.position_mm, o.center_mm) <= o.radius_mm) v.hard = o.hard;
      }
      return absl::OkStatus();
  }
  return absl::InvalidArgumentError("hardness override: unknown shape");
}

}  // namespace

Status ClassifyHardness(const Volume& volume, double R_mm, const ClassifyParams& params,
                        std::vector<MeshVertex>& vertices) {
  for (double t : {params.bone_threshold, params.influence_threshold, params.influence_factor}) {
    if (!std::isfinite(t)) return absl::InvalidArgumentError("classification thresholds must be finite");
  }
  std::vector<int64_t> bone;  // hard by rule 1
  for (size_t i = 0; i < vertices.size(); ++i) {
    auto& v = vertices[i];
    v.hard = v.kind != VertexKind::kAnchor && ValueAt(volume, v) >= params.bone_threshold;
    if (v.hard) bone.push_back(static_cast<int64_t>(i));
  }
  const double radius = params.influence_factor * R_mm;
  std::vector<char> influenced(vertices.size(), 0);
  for (size_t i = 0; i < vertices.size(); ++i) {
    const auto& u = vertices[i];
    if (u.hard || u.kind == VertexKind::kAnchor ||
        ValueAt(volume, u) < params.influence_threshold) {
      continue;
    }
    for (int64_t h : bone) {
      if (PointDistance(u.position_mm, vertices[h].position_mm) < radius) {
        influenced[i] = 1;
        break;
      }
    }
  }
  // Applied after the scan, so influence never chains (one pass, not transitive).
  for (size_t i = 0; i < vertices.size(); ++i) {
    if (influenced[i]) vertices[i].hard = true;
  }
  for (const auto& o : params.overrides) RETURN_IF_ERROR(ApplyOverride(o, vertices));
  return absl::OkStatus();
}

}  // namespace vpm

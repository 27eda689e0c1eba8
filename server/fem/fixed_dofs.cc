#include "server/fem/fixed_dofs.h"

#include <cmath>

namespace vpm {

// Relative distance (of the extent) within which a vertex counts as on a face.
constexpr double kOnFaceRelative = 1e-6;

Result<std::vector<uint8_t>> FixedDofs(const ProxyMesh& mesh, const glm::dvec3& box_extent_mm) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(box_extent_mm[i]) || !(box_extent_mm[i] > 0.0)) {
      return absl::InvalidArgumentError(
          StrCat("box extent must be finite and > 0 on every axis, got ", box_extent_mm[i],
                 " mm on axis ", i));
    }
  }
  std::vector<uint8_t> fixed(3 * mesh.vertices.size(), 0);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const MeshVertex& vertex = mesh.vertices[v];
    const bool all = vertex.skeleton || vertex.kind == VertexKind::kAnchor;
    for (int i = 0; i < 3; ++i) {
      const double p = vertex.position_mm[i];
      if (!std::isfinite(p)) {
        return absl::InvalidArgumentError(StrCat("vertex ", v, " has a non-finite position"));
      }
      const double tolerance = kOnFaceRelative * box_extent_mm[i];
      const bool on_face = std::abs(p) <= tolerance || std::abs(p - box_extent_mm[i]) <= tolerance;
      if (all || on_face) fixed[3 * v + i] = 1;
    }
  }
  return fixed;
}

}  // namespace vpm

#include "server/fem/interpolate_displacement.h"

namespace vpm {

std::optional<glm::dvec3> InterpolateDisplacement(const TetLocator& rest_mesh,
                                                  const std::vector<glm::dvec3>& displacement_mm,
                                                  const glm::dvec3& point_mm) {
  const std::optional<TetLocator::Location> hit = rest_mesh.Locate(point_mm);
  if (!hit.has_value()) return std::nullopt;
  const auto& tet = rest_mesh.tets()[hit->tet];
  glm::dvec3 u(0.0);
  for (int c = 0; c < 4; ++c) u += hit->weights[c] * displacement_mm[tet[c]];
  return u;
}

Result<std::vector<glm::dvec3>> InterpolateDisplacements(
    const TetLocator& rest_mesh, const std::vector<glm::dvec3>& displacement_mm,
    const std::vector<glm::dvec3>& points_mm, const glm::dvec3& outside) {
  if (displacement_mm.size() != rest_mesh.positions().size()) {
    return absl::InvalidArgumentError(StrCat("got ", displacement_mm.size(),
                                             " displacements for a mesh of ",
                                             rest_mesh.positions().size(), " vertices"));
  }
  std::vector<glm::dvec3> out;
  out.reserve(points_mm.size());
  for (const glm::dvec3& p : points_mm) {
    out.push_back(InterpolateDisplacement(rest_mesh, displacement_mm, p).value_or(outside));
  }
  return out;
}

}  // namespace vpm

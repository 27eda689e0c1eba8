#include "server/fem/fem_material.h"

#include <cmath>

#include "server/fem/fem_units.h"

namespace vpm {

Status ValidateMaterial(const FemMaterial& material) {
  if (!std::isfinite(material.young_soft_kpa) || !(material.young_soft_kpa > 0.0)) {
    return absl::InvalidArgumentError(
        StrCat("young_soft_kpa must be finite and > 0, got ", material.young_soft_kpa));
  }
  if (!std::isfinite(material.poisson) || !(material.poisson > -1.0) || !(material.poisson < 0.5)) {
    return absl::InvalidArgumentError(
        StrCat("poisson must lie in (-1, 0.5), got ", material.poisson));
  }
  if (!std::isfinite(material.hard_factor) || !(material.hard_factor >= 1.0)) {
    return absl::InvalidArgumentError(
        StrCat("hard_factor must be finite and >= 1, got ", material.hard_factor));
  }
  return absl::OkStatus();
}

LameParameters Lame(double young, double poisson) {
  return {young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)),
          young / (2.0 * (1.0 + poisson))};
}

Result<std::vector<double>> TetYoungModuli(const ProxyMesh& mesh, const FemMaterial& material) {
  RETURN_IF_ERROR(ValidateMaterial(material));
  const double soft = KpaToNPerMm2(material.young_soft_kpa);
  const double hard = soft * material.hard_factor;
  const auto vertex_count = static_cast<int64_t>(mesh.vertices.size());
  std::vector<double> young(mesh.tets.size(), soft);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    for (int32_t v : mesh.tets[t]) {
      if (v < 0 || v >= vertex_count) {
        return absl::InvalidArgumentError(
            StrCat("tet ", t, " has vertex index ", v, " outside [0, ", vertex_count, ")"));
      }
      if (mesh.vertices[v].hard) young[t] = hard;
    }
  }
  return young;
}

}  // namespace vpm

#include "server/fem/tet_element.h"

#include <cmath>

#include <Eigen/LU>

#include "server/fem/fem_material.h"

namespace vpm {

Result<TetElement> MakeTetElement(const std::array<int32_t, 4>& vertices,
                                  const std::array<glm::dvec3, 4>& rest_mm, double young_n_per_mm2,
                                  double poisson) {
  Eigen::Matrix3d dm;
  for (int c = 0; c < 3; ++c) {
    const glm::dvec3 edge = rest_mm[c + 1] - rest_mm[0];
    dm.col(c) = Eigen::Vector3d(edge.x, edge.y, edge.z);
  }
  const double det = dm.determinant();
  if (!std::isfinite(det) || !(det > 0.0)) {
    return absl::InvalidArgumentError(
        StrCat("tet has non-positive or non-finite volume (det ", det, " mm^3)"));
  }
  if (!std::isfinite(young_n_per_mm2) || !(young_n_per_mm2 > 0.0)) {
    return absl::InvalidArgumentError(StrCat("Young's modulus must be > 0, got ", young_n_per_mm2));
  }
  TetElement element;
  element.vertices = vertices;
  element.volume_mm3 = det / 6.0;
  // X - X0 = Dm xi, so the barycentric coordinates xi_1..3 have gradients
  // equal to the rows of Dm^-1; xi_0 = 1 - xi_1 - xi_2 - xi_3.
  const Eigen::Matrix3d inverse = dm.inverse();
  element.grad_per_mm.rightCols<3>() = inverse.transpose();
  element.grad_per_mm.col(0) = -inverse.transpose().rowwise().sum();
  if (!element.grad_per_mm.allFinite()) {
    return absl::InvalidArgumentError("tet is too flat to invert its edge matrix");
  }
  const LameParameters lame = Lame(young_n_per_mm2, poisson);
  element.lambda_n_per_mm2 = lame.lambda;
  element.mu_n_per_mm2 = lame.mu;
  return element;
}

Result<std::vector<TetElement>> MakeTetElements(const std::vector<glm::dvec3>& rest_mm,
                                                const std::vector<std::array<int32_t, 4>>& tets,
                                                const std::vector<double>& young_n_per_mm2,
                                                double poisson) {
  if (young_n_per_mm2.size() != tets.size()) {
    return absl::InvalidArgumentError(
        StrCat("got ", young_n_per_mm2.size(), " moduli for ", tets.size(), " tets"));
  }
  const auto vertex_count = static_cast<int64_t>(rest_mm.size());
  std::vector<TetElement> elements;
  elements.reserve(tets.size());
  for (size_t t = 0; t < tets.size(); ++t) {
    std::array<glm::dvec3, 4> corners;
    for (int c = 0; c < 4; ++c) {
      const int32_t v = tets[t][c];
      if (v < 0 || v >= vertex_count) {
        return absl::InvalidArgumentError(
            StrCat("tet ", t, " has vertex index ", v, " outside [0, ", vertex_count, ")"));
      }
      corners[c] = rest_mm[v];
    }
    Result<TetElement> element = MakeTetElement(tets[t], corners, young_n_per_mm2[t], poisson);
    if (!element.ok()) {
      return absl::InvalidArgumentError(StrCat("tet ", t, ": ", element.status().message()));
    }
    elements.push_back(*std::move(element));
  }
  return elements;
}

Eigen::Matrix<double, 12, 12> ElementStiffness(const TetElement& element) {
  Eigen::Matrix<double, 12, 12> k;
  const double v = element.volume_mm3;
  const double lambda = element.lambda_n_per_mm2;
  const double mu = element.mu_n_per_mm2;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d ga = element.grad_per_mm.col(a);
    for (int b = 0; b < 4; ++b) {
      const Eigen::Vector3d gb = element.grad_per_mm.col(b);
      k.block<3, 3>(3 * a, 3 * b) = v * (lambda * ga * gb.transpose() + mu * gb * ga.transpose() +
                                         mu * ga.dot(gb) * Eigen::Matrix3d::Identity());
    }
  }
  return k;
}

}  // namespace vpm

#include "server/fem/assemble_stiffness.h"

namespace vpm {
namespace {

// The 12 by 12 element tangent, column by column from the matrix-free product.
Eigen::Matrix<double, 12, 12> ElementTangent(const TetElement& element,
                                             const CorotatedFrames& frames, size_t t) {
  if (frames.rotations.empty()) return ElementStiffness(element);
  const Eigen::Matrix3d* twist = frames.Twist(t);
  Eigen::Matrix<double, 12, 12> k;
  for (int col = 0; col < 12; ++col) {
    Eigen::Matrix<double, 3, 4> unit = Eigen::Matrix<double, 3, 4>::Zero();
    unit(col % 3, col / 3) = 1.0;
    const Eigen::Matrix<double, 3, 4> f =
        ApplyElementTangent(element, frames.rotations[t], twist, unit, frames.Barrier(t));
    for (int a = 0; a < 4; ++a) k.block<3, 1>(3 * a, col) = f.col(a);
  }
  return k;
}

}  // namespace

Eigen::SparseMatrix<double> AssembleStiffness(const std::vector<TetElement>& elements,
                                              const CorotatedFrames& frames, int64_t vertex_count) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(elements.size() * 144);
  for (size_t t = 0; t < elements.size(); ++t) {
    const TetElement& element = elements[t];
    const Eigen::Matrix<double, 12, 12> k = ElementTangent(element, frames, t);
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < 3; ++j) {
            triplets.emplace_back(3 * element.vertices[a] + i, 3 * element.vertices[b] + j,
                                  k(3 * a + i, 3 * b + j));
          }
        }
      }
    }
  }
  Eigen::SparseMatrix<double> stiffness(3 * vertex_count, 3 * vertex_count);
  stiffness.setFromTriplets(triplets.begin(), triplets.end());
  return stiffness;
}

}  // namespace vpm

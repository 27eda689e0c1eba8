// The panel solve of an LDL^T factor against Eigen's own solve of it: bit
// for bit.
#include "server/fem/ldlt_panels.h"

#include <random>

#include <gtest/gtest.h>

#include "server/fem/assemble_stiffness.h"
#include "server/fem/fixed_dofs.h"
#include "tests/fem/fem_test_meshes.h"
#include "tests/fem/random_vector.h"

namespace vpm {
namespace {

using Ldlt = LdltPanels::Ldlt;

// Relative difference of the panel solve from Eigen's, max over a few
// right-hand sides.
double WorstRelativeDifference(const Eigen::SparseMatrix<double>& a) {
  Ldlt ldlt(a);
  EXPECT_EQ(ldlt.info(), Eigen::Success);
  const LdltPanels panels(ldlt);
  EXPECT_EQ(panels.size(), a.rows());
  double worst = 0.0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const Eigen::VectorXd b = testing::RandomNormalVector(a.rows(), seed);
    const Eigen::VectorXd expected = ldlt.solve(b);
    Eigen::VectorXd x;
    panels.Solve(b, x);
    // Eigen's operations in Eigen's order: the same doubles.
    EXPECT_TRUE((x.array() == expected.array()).all()) << "seed " << seed;
    worst = std::max(worst, (x - expected).norm() / expected.norm());
  }
  return worst;
}

// The free block of a tet mesh's stiffness (3 DOFs per vertex, as the FEM
// factors it): AMD keeps a vertex's DOFs together, so panels are wide.
Eigen::SparseMatrix<double> MeshFreeBlock(int vertices, unsigned seed) {
  const glm::dvec3 extent(20.0, 15.0, 10.0);
  const ProxyMesh mesh = testing::RandomBoxMesh(vertices, 5, extent, seed);
  const std::vector<double> moduli(mesh.tets.size(), 0.005);
  const auto elements = *MakeTetElements(testing::RestPositions(mesh), mesh.tets, moduli, 0.45);
  const Eigen::SparseMatrix<double> k = AssembleStiffness(elements, {}, mesh.vertices.size());
  const std::vector<uint8_t> fixed = *FixedDofs(mesh, extent);
  std::vector<int> compact(fixed.size(), -1);
  int m = 0;
  for (size_t d = 0; d < fixed.size(); ++d) {
    if (!fixed[d]) compact[d] = m++;
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (int col = 0; col < k.outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(k, col); it; ++it) {
      if (compact[it.row()] >= 0 && compact[col] >= 0) {
        triplets.emplace_back(compact[it.row()], compact[col], it.value());
      }
    }
  }
  Eigen::SparseMatrix<double> free_block(m, m);
  free_block.setFromTriplets(triplets.begin(), triplets.end());
  return free_block;
}

TEST(LdltPanels, SolvesAsEigenOnAMeshStiffness) {
  const Eigen::SparseMatrix<double> a = MeshFreeBlock(200, 4);
  EXPECT_LT(WorstRelativeDifference(a), 1e-12);
  // Panels hold several columns each on average.
  Ldlt ldlt(a);
  EXPECT_LT(LdltPanels(ldlt).panel_count(), a.rows() / 2);
}

// Rows and columns decoupled as ConstrainedFactor's handles (off-diagonal
// values 0, the pattern kept): explicit zeros in L.
TEST(LdltPanels, SolvesAsEigenWithDecoupledRows) {
  Eigen::SparseMatrix<double> a = MeshFreeBlock(120, 9);
  std::vector<uint8_t> decoupled(a.rows(), 0);
  for (int64_t i = 0; i < a.rows(); i += 7) decoupled[i] = 1;
  for (int64_t col = 0; col < a.outerSize(); ++col) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, col); it; ++it) {
      if (it.row() != col && (decoupled[it.row()] || decoupled[col])) it.valueRef() = 0.0;
    }
  }
  EXPECT_LT(WorstRelativeDifference(a), 1e-12);
}

// A random sparse SPD matrix (no block structure: mostly 1-column panels)
// and the smallest sizes.
TEST(LdltPanels, SolvesAsEigenOnRandomAndTinyMatrices) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pick(0, 299);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::vector<Eigen::Triplet<double>> triplets;
  for (int i = 0; i < 300; ++i) triplets.emplace_back(i, i, 40.0);
  for (int e = 0; e < 900; ++e) {
    const int i = pick(rng), j = pick(rng);
    if (i == j) continue;
    const double v = value(rng);
    triplets.emplace_back(i, j, v);
    triplets.emplace_back(j, i, v);
  }
  Eigen::SparseMatrix<double> a(300, 300);
  a.setFromTriplets(triplets.begin(), triplets.end());
  EXPECT_LT(WorstRelativeDifference(a), 1e-12);
  for (int n : {1, 2, 9}) {
    Eigen::SparseMatrix<double> dense(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) dense.insert(i, j) = i == j ? 4.0 : 1.0 / (1 + i + j);
    }
    EXPECT_LT(WorstRelativeDifference(dense), 1e-12) << n;
  }
}

}  // namespace
}  // namespace vpm

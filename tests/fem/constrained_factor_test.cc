// The factor-once preconditioner: exact inverse for any extra constrained set.
#include "server/fem/constrained_factor.h"

#include <random>

#include <gtest/gtest.h>
#include <Eigen/Cholesky>

#include "server/fem/assemble_stiffness.h"
#include "server/fem/fixed_dofs.h"
#include "tests/fem/fem_test_meshes.h"
#include "tests/fem/random_vector.h"

namespace vpm {
namespace {

using testing::RandomBoxMesh;
using testing::RestPositions;

struct Problem {
  Eigen::SparseMatrix<double> k;
  std::vector<uint8_t> fixed;
};

Problem MakeProblem() {
  const glm::dvec3 extent(20.0, 15.0, 10.0);
  const ProxyMesh mesh = RandomBoxMesh(60, 5, extent, 12);
  const std::vector<double> moduli(mesh.tets.size(), 0.005);
  const auto elements = *MakeTetElements(RestPositions(mesh), mesh.tets, moduli, 0.45);
  return {AssembleStiffness(elements, {}, mesh.vertices.size()), *FixedDofs(mesh, extent)};
}

// z = K_SS^-1 r_S by a dense solve, 0 outside S.
Eigen::VectorXd DenseReference(const Eigen::MatrixXd& k, const std::vector<uint8_t>& constrained,
                               const Eigen::VectorXd& r) {
  std::vector<int> s;
  for (size_t d = 0; d < constrained.size(); ++d) {
    if (!constrained[d]) s.push_back(static_cast<int>(d));
  }
  Eigen::MatrixXd kss(s.size(), s.size());
  Eigen::VectorXd rs(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    rs[i] = r[s[i]];
    for (size_t j = 0; j < s.size(); ++j) kss(i, j) = k(s[i], s[j]);
  }
  const Eigen::VectorXd zs = kss.ldlt().solve(rs);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(r.size());
  for (size_t i = 0; i < s.size(); ++i) z[s[i]] = zs[i];
  return z;
}

TEST(ConstrainedFactor, ExtraConstraintsGiveTheExactSubBlockInverse) {
  const Problem setup = MakeProblem();
  auto factor = ConstrainedFactor::Create(setup.k, setup.fixed);
  ASSERT_TRUE(factor.ok()) << factor.status();
  const Eigen::MatrixXd dense(setup.k);
  const Eigen::VectorXd r = testing::RandomNormalVector(setup.k.rows(), 1);
  Eigen::VectorXd z;
  factor->Apply(r, false, z);
  Eigen::VectorXd expected = DenseReference(dense, setup.fixed, r);
  EXPECT_LT((z - expected).norm(), 1e-9 * expected.norm());
  // Handles: a handful of free DOFs become constrained, no refactoring.
  std::vector<int32_t> extra;
  std::vector<uint8_t> constrained = setup.fixed;
  for (int64_t d = 5; d < r.size() && extra.size() < 12; d += 17) {
    if (setup.fixed[d]) continue;
    extra.push_back(static_cast<int32_t>(d));
    constrained[d] = 1;
  }
  ASSERT_TRUE(factor->SetExtraFixed(extra).ok());
  factor->Apply(r, true, z);
  expected = DenseReference(dense, constrained, r);
  EXPECT_LT((z - expected).norm(), 1e-9 * expected.norm());
  for (int32_t d : extra) EXPECT_EQ(z[d], 0.0);
  // Without them again.
  factor->Apply(r, false, z);
  EXPECT_LT((z - DenseReference(dense, setup.fixed, r)).norm(), 1e-9 * expected.norm());
}

// The two ways of taking the handles (a capacitance correction of the base
// factor, a numeric refactorization with the handles decoupled) give the
// same inverse, before and after the handle set changes.
TEST(ConstrainedFactor, RefactoredAndCapacitanceHandlesAgree) {
  const Problem setup = MakeProblem();
  auto refactor = ConstrainedFactor::Create(setup.k, setup.fixed, HandleFactor::kRefactor);
  auto capacitance = ConstrainedFactor::Create(setup.k, setup.fixed, HandleFactor::kCapacitance);
  ASSERT_TRUE(refactor.ok()) << refactor.status();
  ASSERT_TRUE(capacitance.ok()) << capacitance.status();
  const Eigen::MatrixXd dense(setup.k);
  const Eigen::VectorXd r = testing::RandomNormalVector(setup.k.rows(), 3);
  for (int64_t first : {3, 8}) {
    std::vector<int32_t> extra;
    std::vector<uint8_t> constrained = setup.fixed;
    for (int64_t d = first; d < r.size() && extra.size() < 20; d += 11) {
      if (setup.fixed[d]) continue;
      extra.push_back(static_cast<int32_t>(d));
      constrained[d] = 1;
    }
    ASSERT_TRUE(refactor->SetExtraFixed(extra).ok());
    ASSERT_TRUE(capacitance->SetExtraFixed(extra).ok());
    Eigen::VectorXd z_refactor, z_capacitance;
    refactor->Apply(r, true, z_refactor);
    capacitance->Apply(r, true, z_capacitance);
    const Eigen::VectorXd expected = DenseReference(dense, constrained, r);
    EXPECT_LT((z_refactor - expected).norm(), 1e-9 * expected.norm());
    EXPECT_LT((z_refactor - z_capacitance).norm(), 1e-9 * expected.norm());
    for (int32_t d : extra) EXPECT_EQ(z_refactor[d], 0.0);
    // Without the handles: the base factor, untouched by the refactorization.
    refactor->Apply(r, false, z_refactor);
    const Eigen::VectorXd base = DenseReference(dense, setup.fixed, r);
    EXPECT_LT((z_refactor - base).norm(), 1e-9 * base.norm());
  }
  ASSERT_TRUE(refactor->SetExtraFixed({}).ok());
  Eigen::VectorXd z;
  refactor->Apply(r, true, z);
  const Eigen::VectorXd base = DenseReference(dense, setup.fixed, r);
  EXPECT_LT((z - base).norm(), 1e-9 * base.norm());
}

TEST(ConstrainedFactor, RejectsFreeRigidMotionsAndBadExtraDofs) {
  const Problem setup = MakeProblem();
  const std::vector<uint8_t> nothing_fixed(setup.fixed.size(), 0);
  const auto singular = ConstrainedFactor::Create(setup.k, nothing_fixed);
  EXPECT_EQ(singular.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(singular.status().message().find("rigid motion"), std::string::npos);
  const std::vector<uint8_t> all_fixed(setup.fixed.size(), 1);
  EXPECT_EQ(ConstrainedFactor::Create(setup.k, all_fixed).status().code(),
            absl::StatusCode::kFailedPrecondition);
  auto factor = ConstrainedFactor::Create(setup.k, setup.fixed);
  ASSERT_TRUE(factor.ok());
  int32_t fixed_dof = 0;
  while (!setup.fixed[fixed_dof]) ++fixed_dof;
  int32_t free_dof = 0;
  while (setup.fixed[free_dof]) ++free_dof;
  EXPECT_EQ(factor->SetExtraFixed({fixed_dof}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(factor->SetExtraFixed({free_dof, free_dof}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(factor->SetExtraFixed({-1}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(factor->SetExtraFixed({free_dof}).ok());
}

}  // namespace
}  // namespace vpm

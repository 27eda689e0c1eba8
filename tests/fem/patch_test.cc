// Patch test: an affine displacement prescribed on the boundary of an
// irregular mesh is reproduced exactly inside, by linear and by corotational
// FEM (uniform F gives uniform stress, whose nodal forces cancel inside).
#include <cmath>

#include <gtest/gtest.h>

#include "server/fem/corotational_solver.h"
#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::At;
using testing::OnBoxSurface;
using testing::RandomBoxMesh;
using testing::RestPositions;
using testing::Rotation;

SolverOptions Tight(bool corotational) {
  SolverOptions options;
  options.method = corotational ? FemMethod::kCorotationalConsistent : FemMethod::kLinear;
  options.update_tolerance = 1e-13;
  options.cg_tolerance = 1e-12;
  options.max_newton_iterations = 100;
  return options;
}

// u(X) = A (X - c) + b at every vertex, 3*#V.
Eigen::VectorXd Affine(const std::vector<glm::dvec3>& rest, const Eigen::Matrix3d& a,
                       const Eigen::Vector3d& b, const glm::dvec3& c) {
  Eigen::VectorXd u(3 * rest.size());
  for (size_t v = 0; v < rest.size(); ++v) {
    const glm::dvec3 x = rest[v] - c;
    u.segment<3>(3 * v) = a * Eigen::Vector3d(x.x, x.y, x.z) + b;
  }
  return u;
}

void RunPatch(bool corotational, double scale) {
  const glm::dvec3 extent = glm::dvec3(20.0, 16.0, 12.0) * scale;
  const ProxyMesh mesh = RandomBoxMesh(80, 6, extent, 21);
  ASSERT_FALSE(mesh.tets.empty());
  const auto rest = RestPositions(mesh);
  std::vector<uint8_t> fixed(3 * rest.size(), 0);
  int interior = 0;
  for (size_t v = 0; v < rest.size(); ++v) {
    const bool boundary = OnBoxSurface(rest[v], extent);
    for (int i = 0; i < 3; ++i) fixed[3 * v + i] = boundary;
    interior += !boundary;
  }
  ASSERT_GT(interior, 50);
  const std::vector<double> moduli(mesh.tets.size(), 0.005);
  auto solver =
      CorotationalSolver::Create(rest, mesh.tets, moduli, 0.45, fixed, Tight(corotational));
  ASSERT_TRUE(solver.ok()) << solver.status();
  Eigen::Matrix3d stretch;
  stretch << 0.04, 0.01, -0.02, 0.01, -0.03, 0.015, -0.02, 0.015, 0.05;
  const double angle = corotational ? 0.5 : 0.0;  // linear FEM: small strain only
  const Eigen::Vector3d shift = Eigen::Vector3d(0.3, -0.2, 0.1) * scale;
  const int steps = 4;
  Eigen::VectorXd expected;
  for (int s = 1; s <= steps; ++s) {
    const double t = static_cast<double>(s) / steps;
    const Eigen::Matrix3d a = Rotation(Eigen::Vector3d(1.0, 2.0, 3.0), t * angle) *
                                  (Eigen::Matrix3d::Identity() + t * stretch) -
                              Eigen::Matrix3d::Identity();
    expected = Affine(rest, a, t * shift, extent * 0.5);
    auto stats =
        solver->Solve(expected, Eigen::VectorXd::Zero(expected.size()), HandleMode::kPrescribed);
    ASSERT_TRUE(stats.ok()) << stats.status();
    EXPECT_TRUE(stats->converged) << "step " << s;
  }
  const double largest = expected.cwiseAbs().maxCoeff();
  const Eigen::VectorXd& u = solver->displacement_mm();
  for (size_t v = 0; v < rest.size(); ++v) {
    EXPECT_LT(glm::length(At(u, v) - At(expected, v)), 1e-9 * largest) << "vertex " << v;
  }
}

TEST(Patch, LinearFemReproducesAnAffineFieldInside) {
  for (double scale : {1e-3, 1.0, 1e3}) {
    SCOPED_TRACE(scale);
    RunPatch(false, scale);
  }
}

TEST(Patch, CorotationalFemReproducesARotatedAffineFieldInside) {
  for (double scale : {1e-3, 1.0, 1e3}) {
    SCOPED_TRACE(scale);
    RunPatch(true, scale);
  }
}

}  // namespace
}  // namespace vpm

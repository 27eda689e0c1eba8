// Large rotations: a rigid rotation of a cube by 90 degrees costs no energy
// with the corotational method; plain linear FEM sees spurious stress and,
// where the boundary is free, deforms the body instead of turning it.
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "server/fem/corotated_forces.h"
#include "server/fem/corotational_solver.h"
#include "server/fem/fem_units.h"
#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::At;
using testing::GridMesh;
using testing::OnBoxSurface;
using testing::RestPositions;
using testing::Rotation;

constexpr double kSide = 20.0;  // mm
const Eigen::Vector3d kAxis(1.0, 1.0, 0.3);

// Displacement of the rigid rotation by `angle` about the cube's centre.
Eigen::VectorXd RigidRotation(const std::vector<glm::dvec3>& rest, double angle) {
  const Eigen::Matrix3d q = Rotation(kAxis, angle);
  const Eigen::Vector3d c(kSide / 2, kSide / 2, kSide / 2);
  Eigen::VectorXd u(3 * rest.size());
  for (size_t v = 0; v < rest.size(); ++v) {
    const Eigen::Vector3d x(rest[v].x, rest[v].y, rest[v].z);
    u.segment<3>(3 * v) = q * (x - c) + c - x;
  }
  return u;
}

struct Outcome {
  double max_error_mm = 0.0;  // max vertex distance from the rigid rotation
  double energy_ratio = 0.0;  // energy / (E * volume), dimensionless
  bool converged = true;
};

// Turns the cube to 90 degrees in `steps` steps with the vertices selected
// by `prescribe` following the rigid rotation, the rest free.
Outcome Turn(bool corotational, int steps, bool (*prescribe)(const glm::dvec3&)) {
  const ProxyMesh mesh = GridMesh({4, 4, 4}, glm::dvec3(kSide));
  const auto rest = RestPositions(mesh);
  std::vector<uint8_t> fixed(3 * rest.size(), 0);
  for (size_t v = 0; v < rest.size(); ++v) {
    for (int i = 0; i < 3; ++i) fixed[3 * v + i] = prescribe(rest[v]);
  }
  const double young = KpaToNPerMm2(5.0);
  SolverOptions options;
  options.method = corotational ? FemMethod::kCorotationalConsistent : FemMethod::kLinear;
  options.update_tolerance = 1e-12;
  options.cg_tolerance = 1e-10;
  options.max_newton_iterations = 200;
  auto solver = *CorotationalSolver::Create(
      rest, mesh.tets, std::vector<double>(mesh.tets.size(), young), 0.45, fixed, options);
  Outcome outcome;
  Eigen::VectorXd target;
  for (int s = 1; s <= steps; ++s) {
    target = RigidRotation(rest, 0.5 * std::numbers::pi * s / steps);
    auto stats =
        solver.Solve(target, Eigen::VectorXd::Zero(target.size()), HandleMode::kPrescribed);
    EXPECT_TRUE(stats.ok()) << stats.status();
    outcome.converged = outcome.converged && stats.ok() && stats->converged;
  }
  const Eigen::VectorXd& u = solver.displacement_mm();
  for (size_t v = 0; v < rest.size(); ++v) {
    outcome.max_error_mm = std::max(outcome.max_error_mm, glm::length(At(u, v) - At(target, v)));
  }
  // Each method's own elastic energy (R = I for linear FEM).
  CorotatedFrames frames;
  Eigen::VectorXd forces;
  CorotatedForces(solver.elements(), u, options.method, frames, forces);
  outcome.energy_ratio =
      CorotatedEnergy(solver.elements(), frames.rotations, u) / (young * kSide * kSide * kSide);
  return outcome;
}

bool Surface(const glm::dvec3& p) { return OnBoxSurface(p, glm::dvec3(kSide)); }
bool Bottom(const glm::dvec3& p) { return p.z == 0.0; }

TEST(LargeRotation, CorotationalRotationOfTheBoundaryCausesNoStress) {
  const Outcome corotational = Turn(true, 9, Surface);
  EXPECT_TRUE(corotational.converged);
  EXPECT_LT(corotational.max_error_mm, 1e-9 * kSide);
  EXPECT_LT(corotational.energy_ratio, 1e-18);
  // Linear FEM reproduces the (affine) motion inside but stores a large,
  // spurious elastic energy in it.
  const Outcome linear = Turn(false, 1, Surface);
  EXPECT_LT(linear.max_error_mm, 1e-9 * kSide);
  EXPECT_GT(linear.energy_ratio, 1e-2);
  std::printf("all-boundary 90 deg: energy/(E V) corotational %.2e, linear %.2e\n",
              corotational.energy_ratio, linear.energy_ratio);
}

TEST(LargeRotation, TurningOneFaceTurnsTheBodyRigidlyOnlyWhenCorotated) {
  const Outcome corotational = Turn(true, 18, Bottom);
  EXPECT_TRUE(corotational.converged);
  EXPECT_LT(corotational.max_error_mm, 1e-8 * kSide);
  const Outcome linear = Turn(false, 1, Bottom);
  EXPECT_GT(linear.max_error_mm, 0.05 * kSide);
  std::printf(
      "bottom face turned 90 deg: max distance from the rigid motion: corotational "
      "%.2e mm, linear %.2f mm (cube %.0f mm)\n",
      corotational.max_error_mm, linear.max_error_mm, kSide);
}

}  // namespace
}  // namespace vpm

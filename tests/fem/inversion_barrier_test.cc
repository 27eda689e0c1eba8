// The inversion barrier: inactive above its onset, smooth there, forces that
// are its energy's gradient, a positive semi-definite tangent, steps that
// keep every element positive, and drags of 1.5 h that invert nothing.
#include "server/fem/inversion_barrier.h"

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "server/fem/corotated_forces.h"
#include "server/fem/corotational_solver.h"
#include "server/fem/fem_model.h"
#include "server/mesh/build_proxy_mesh.h"
#include "tests/fem/fem_test_meshes.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

constexpr double kYoung = 0.005;  // N/mm^2 (5 kPa)

// One element on the unit right tet (mm).
TetElement UnitTet() {
  return *MakeTetElement(
      {0, 1, 2, 3},
      {glm::dvec3(0, 0, 0), glm::dvec3(1, 0, 0), glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)}, kYoung,
      0.45);
}

// Corner displacements (3*4, mm) that scale the unit tet by `ratio` along z
// and shear it: volume ratio J = ratio.
Eigen::VectorXd Squash(double ratio) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(12);
  u[3 * 3 + 2] = ratio - 1.0;  // vertex 3 (0,0,1) -> (0.3,-0.2,ratio)
  u[3 * 3 + 0] = 0.3;
  u[3 * 3 + 1] = -0.2;
  return u;
}

TEST(InversionBarrier, IsInactiveAtAndAboveTheOnsetAndSmoothThere) {
  const TetElement tet = UnitTet();
  for (double j : {1.0, 0.5, kBarrierOnsetVolumeRatio}) {
    EXPECT_NEAR(VolumeRatio(tet, Squash(j)), j, 1e-12);
    EXPECT_FALSE(EvaluateBarrier(tet, Eigen::Matrix3d::Identity() * std::cbrt(j)).active) << j;
  }
  // Just below J0 energy, force and curvature all start from 0 (C2).
  const BarrierTerm near = EvaluateBarrier(
      tet, Eigen::Matrix3d::Identity() * std::cbrt(kBarrierOnsetVolumeRatio - 1e-6));
  ASSERT_TRUE(near.active);
  const double k = tet.lambda_n_per_mm2 + 2.0 * tet.mu_n_per_mm2;
  EXPECT_LT(near.energy_n_mm, 1e-10 * k * tet.volume_mm3);
  EXPECT_LT(std::abs(near.stress_scale_n_per_mm2), 1e-4 * k);
  EXPECT_LT(near.curvature_n_per_mm2, 1e-3 * k);
  // And it grows without bound towards J = 0.
  const BarrierTerm deep = EvaluateBarrier(tet, Eigen::Matrix3d::Identity() * std::cbrt(1e-6));
  EXPECT_LT(deep.stress_scale_n_per_mm2, -1e3 * k);
  // An inverted element is not the barrier's (it never lets one happen).
  EXPECT_FALSE(EvaluateBarrier(tet, -Eigen::Matrix3d::Identity()).active);
}

TEST(InversionBarrier, ForcesAreTheGradientOfTheEnergy) {
  const std::vector<TetElement> elements{UnitTet()};
  for (double j : {0.2, 0.05, 0.002}) {
    const Eigen::VectorXd u = Squash(j);
    CorotatedFrames frames;
    Eigen::VectorXd forces, with_barrier;
    CorotatedForces(elements, u, FemMethod::kCorotational, frames, forces);
    CorotatedForces(elements, u, FemMethod::kCorotational, frames, with_barrier, 1, true);
    ASSERT_TRUE(frames.Barrier(0) != nullptr) << j;
    EXPECT_GT((with_barrier - forces).norm(), 1e-3 * forces.norm()) << j;
    auto energy = [&](const Eigen::VectorXd& w) {
      CorotatedFrames f;
      Eigen::VectorXd unused;
      CorotatedForces(elements, w, FemMethod::kCorotational, f, unused, 1, true);
      return CorotatedEnergy(elements, f.rotations, w, true);
    };
    const double step = 1e-4 * j;
    for (int i = 0; i < 12; ++i) {
      Eigen::VectorXd plus = u, minus = u;
      plus[i] += step;
      minus[i] -= step;
      const double numeric = (energy(plus) - energy(minus)) / (2.0 * step);
      EXPECT_NEAR(with_barrier[i], numeric, 1e-6 * with_barrier.cwiseAbs().maxCoeff())
          << "J " << j << " dof " << i;
    }
  }
}

TEST(InversionBarrier, TangentIsSymmetricPositiveSemiDefiniteAndResistsCollapse) {
  const TetElement tet = UnitTet();
  const Eigen::Matrix3d f =
      Eigen::Matrix3d::Identity() +
      DisplacementGradient(tet, Eigen::Matrix<double, 3, 4>(Squash(0.05).reshaped(3, 4)));
  const BarrierTerm term = EvaluateBarrier(tet, f);
  ASSERT_TRUE(term.active);
  Eigen::Matrix<double, 12, 12> k;
  for (int col = 0; col < 12; ++col) {
    Eigen::Matrix<double, 3, 4> unit = Eigen::Matrix<double, 3, 4>::Zero();
    unit(col % 3, col / 3) = 1.0;
    k.col(col) = ApplyBarrierTangent(tet, term, unit).reshaped();
  }
  EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> eigen(k);
  EXPECT_GT(eigen.eigenvalues().minCoeff(), -1e-12 * k.norm());
  // Moving the apex further down (towards collapse) costs positive work.
  Eigen::Matrix<double, 3, 4> down = Eigen::Matrix<double, 3, 4>::Zero();
  down(2, 3) = -1.0;
  EXPECT_GT(down.reshaped().dot(ApplyBarrierTangent(tet, term, down).reshaped()), 0.0);
}

TEST(InversionBarrier, FeasibleStepKeepsEveryElementPositive) {
  const std::vector<TetElement> elements{UnitTet()};
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(12);
  Eigen::VectorXd through = Eigen::VectorXd::Zero(12);
  through[3 * 3 + 2] = -3.0;  // apex 3 mm down: J = -2 at the full step
  const double alpha = FeasibleStepFraction(elements, rest, through);
  ASSERT_GT(alpha, 0.0);
  EXPECT_LE(alpha, 0.5);
  EXPECT_GE(VolumeRatio(elements[0], rest + alpha * through), 0.2 * kBarrierOnsetVolumeRatio);
  EXPECT_LT(VolumeRatio(elements[0], rest + 2.0 * alpha * through),
            0.2 * kBarrierOnsetVolumeRatio);  // the largest power of 2 that works
  EXPECT_EQ(FeasibleStepFraction(elements, rest, -through), 1.0);  // stretching is free
  EXPECT_EQ(FeasibleStepFraction(elements, rest, Eigen::VectorXd::Zero(12)), 1.0);
}

TEST(InversionBarrier, LoadStepOptionsOutOfRangeAreInvalidArgument) {
  const std::vector<glm::dvec3> rest = {glm::dvec3(0, 0, 0), glm::dvec3(1, 0, 0),
                                        glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1)};
  const std::vector<std::array<int32_t, 4>> tets = {{0, 1, 2, 3}};
  std::vector<uint8_t> fixed(12, 0);
  for (int d = 0; d < 9; ++d) fixed[d] = 1;  // vertices 0-2 fixed
  ASSERT_TRUE(CorotationalSolver::Create(rest, tets, {kYoung}, 0.45, fixed).ok());
  for (int bad = 0; bad < 4; ++bad) {
    SolverOptions options;
    if (bad == 0) options.max_load_steps = 0;
    if (bad == 1) options.min_load_fraction = 0.0;
    if (bad == 2) options.min_load_fraction = 1.5;
    if (bad == 3) options.intermediate_newton_iterations = 0;
    EXPECT_EQ(CorotationalSolver::Create(rest, tets, {kYoung}, 0.45, fixed, options).status().code(),
              absl::StatusCode::kInvalidArgument)
        << bad;
  }
}

// The validity measure of docs/ALGORITHM.md section 6 on a small body: a ball of
// handles dragged 1.5 h. The plain corotated model crushes tets in front of
// it; with the barrier the drag is reached and every tet stays positive:
// taken at once with the measurement settings (up to 64 load steps), and in
// 10 increments, as a user drags, with the interactive defaults (4 load
// steps per increment).
TEST(InversionBarrier, ProxyMeshDragOfOneAndAHalfHInvertsNoTet) {
  const Volume volume = testing::MakeBodyVolume();
  const glm::dvec3 point = volume.geometry().extent_mm() * 0.5;
  auto mesh = testing::CentreRefinedMesh(volume);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  const double h = mesh->stats.h_mm;
  const glm::dvec3 drag(1.5 * h, 0.0, 0.0);
  struct Case {
    const char* name;
    bool barrier;
    SolverOptions solver;
    int increments;
  };
  SolverOptions measuring = SolverOptions{};
  measuring.max_load_steps = 64;
  measuring.intermediate_newton_iterations = measuring.max_newton_iterations;
  const Case cases[] = {{"no barrier, at once", false, measuring, 1},
                        {"barrier, at once, 64 load steps", true, measuring, 1},
                        {"barrier, 10 increments, defaults", true, SolverOptions{}, 10}};
  int64_t inverted_without = -1;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    FemOptions options;
    options.solver = c.solver;
    options.solver.inversion_barrier = c.barrier;
    auto model = FemModel::Create(*mesh, volume.geometry().extent_mm(), options);
    ASSERT_TRUE(model.ok()) << model.status();
    const auto grab = model->Grab(point, h);
    ASSERT_TRUE(grab.ok()) << grab.status();
    int barrier_work = 0;
    for (int i = 1; i <= c.increments; ++i) {
      const auto stats = model->Drag(drag * (static_cast<double>(i) / c.increments));
      ASSERT_TRUE(stats.ok()) << stats.status();
      EXPECT_FALSE(stats->forced_inversion) << "increment " << i;
      barrier_work += stats->load_steps - 1 + stats->shortened_updates;
    }
    // The handles reached the prescribed drag.
    const auto u = model->Displacements();
    for (int32_t v : grab->handles) EXPECT_NEAR(glm::length(u[v] - drag), 0.0, 1e-9) << v;
    if (c.barrier) {
      EXPECT_EQ(model->CountInvertedTets(), 0);
      EXPECT_GT(barrier_work, 0);  // the barrier did work
    } else {
      inverted_without = model->CountInvertedTets();
    }
  }
  EXPECT_GT(inverted_without, 0) << "the drag no longer tests the barrier";
}

}  // namespace
}  // namespace vpm

// Element and global stiffness: symmetry, semi-definiteness, rigid-motion
// null space, matrix-free products, forces as the energy gradient.
#include "server/fem/assemble_stiffness.h"

#include <random>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "server/fem/corotated_forces.h"
#include "server/fem/fem_material.h"
#include "server/fem/tet_element.h"
#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::RandomBoxMesh;
using testing::RestPositions;
using testing::Rotation;

std::vector<TetElement> Elements(const ProxyMesh& mesh, double young = 0.005,
                                 double poisson = 0.45) {
  const std::vector<double> moduli(mesh.tets.size(), young);
  return *MakeTetElements(RestPositions(mesh), mesh.tets, moduli, poisson);
}

// The 6 rigid motions (3 translations, 3 infinitesimal rotations about the
// centroid) of the points, as 3*#V columns.
Eigen::MatrixXd RigidMotions(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const auto& p : points) centre += p / static_cast<double>(points.size());
  Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(3 * points.size(), 6);
  for (size_t v = 0; v < points.size(); ++v) {
    for (int i = 0; i < 3; ++i) {
      modes(3 * v + i, i) = 1.0;
      Eigen::Vector3d axis = Eigen::Vector3d::Zero();
      axis[i] = 1.0;
      modes.block<3, 1>(3 * v, 3 + i) = axis.cross(points[v] - centre);
    }
  }
  return modes;
}

std::vector<Eigen::Vector3d> ToEigen(const std::vector<glm::dvec3>& p) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& q : p) out.emplace_back(q.x, q.y, q.z);
  return out;
}

TEST(Stiffness, ElementMatchesVolumeTimesBTransposeDB) {
  const ProxyMesh mesh = RandomBoxMesh(5, 0, glm::dvec3(3.0, 2.0, 4.0), 1);
  for (const TetElement& e : Elements(mesh, 0.7, 0.3)) {
    Eigen::Matrix<double, 6, 12> b = Eigen::Matrix<double, 6, 12>::Zero();  // Voigt strain
    for (int a = 0; a < 4; ++a) {
      const Eigen::Vector3d g = e.grad_per_mm.col(a);
      b(0, 3 * a) = g.x(), b(1, 3 * a + 1) = g.y(), b(2, 3 * a + 2) = g.z();
      b(3, 3 * a + 1) = g.z(), b(3, 3 * a + 2) = g.y();
      b(4, 3 * a) = g.z(), b(4, 3 * a + 2) = g.x();
      b(5, 3 * a) = g.y(), b(5, 3 * a + 1) = g.x();
    }
    Eigen::Matrix<double, 6, 6> d = Eigen::Matrix<double, 6, 6>::Zero();
    d.topLeftCorner<3, 3>().setConstant(e.lambda_n_per_mm2);
    d.topLeftCorner<3, 3>() += 2.0 * e.mu_n_per_mm2 * Eigen::Matrix3d::Identity();
    d.bottomRightCorner<3, 3>() = e.mu_n_per_mm2 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 12, 12> expected = e.volume_mm3 * b.transpose() * d * b;
    EXPECT_LT((ElementStiffness(e) - expected).norm(), 1e-12 * expected.norm());
  }
}

TEST(Stiffness, RigidMotionsAreInTheNullSpace) {
  for (double scale : {1e-3, 1.0, 1e3}) {
    SCOPED_TRACE(scale);
    const glm::dvec3 extent = glm::dvec3(30.0, 20.0, 25.0) * scale;
    const ProxyMesh mesh = RandomBoxMesh(40, 4, extent, 7);
    ASSERT_FALSE(mesh.tets.empty());
    const auto n = static_cast<int64_t>(mesh.vertices.size());
    const Eigen::SparseMatrix<double> k = AssembleStiffness(Elements(mesh), CorotatedFrames{}, n);
    const Eigen::MatrixXd dense = Eigen::MatrixXd(k);
    const double k_norm = dense.norm();
    EXPECT_LT((dense - dense.transpose()).norm(), 1e-14 * k_norm);
    const Eigen::MatrixXd modes = RigidMotions(ToEigen(RestPositions(mesh)));
    for (int m = 0; m < 6; ++m) {
      EXPECT_LT((k * modes.col(m)).norm(), 1e-12 * k_norm * modes.col(m).norm()) << "mode " << m;
    }
    // Positive semi-definite with exactly the 6 rigid motions as null space.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
    const Eigen::VectorXd lambda = eig.eigenvalues();
    const double largest = lambda.maxCoeff();
    EXPECT_GT(lambda.minCoeff(), -1e-12 * largest);
    EXPECT_LT(lambda[5], 1e-12 * largest);
    EXPECT_GT(lambda[6], 1e-8 * largest);
  }
}

TEST(Stiffness, RigidlyRotatedBodyHasNoForceAndRotatedNullSpace) {
  const glm::dvec3 extent(30.0, 20.0, 25.0);
  const ProxyMesh mesh = RandomBoxMesh(40, 4, extent, 8);
  const auto elements = Elements(mesh);
  const auto rest = ToEigen(RestPositions(mesh));
  const Eigen::Matrix3d q = Rotation(Eigen::Vector3d(1.0, -2.0, 0.5), 1.3);
  Eigen::VectorXd u(3 * rest.size());
  std::vector<Eigen::Vector3d> moved;
  for (size_t v = 0; v < rest.size(); ++v) {
    moved.push_back(q * rest[v] + Eigen::Vector3d(4.0, -1.0, 2.0));
    u.segment<3>(3 * v) = moved.back() - rest[v];
  }
  CorotatedFrames frames;
  Eigen::VectorXd forces;
  CorotatedForces(elements, u, FemMethod::kCorotationalConsistent, frames, forces);
  for (const auto& r : frames.rotations) EXPECT_LT((r - q).norm(), 1e-12);
  const Eigen::SparseMatrix<double> k0 =
      AssembleStiffness(elements, CorotatedFrames{}, rest.size());
  const double k_norm = Eigen::MatrixXd(k0).norm();
  EXPECT_LT(forces.norm(), 1e-12 * k_norm * u.norm());
  EXPECT_LT(CorotatedEnergy(elements, frames.rotations, u), 1e-24 * k_norm * u.squaredNorm());
  // Plain linear FEM sees a large spurious strain in the same motion.
  CorotatedFrames identity;
  Eigen::VectorXd linear_forces;
  CorotatedForces(elements, u, FemMethod::kLinear, identity, linear_forces);
  EXPECT_GT(linear_forces.norm(), 1e-3 * k_norm * u.norm());
  // The tangent there is Q K0 Q^T (no twist term at zero strain).
  const Eigen::SparseMatrix<double> k = AssembleStiffness(elements, frames, rest.size());
  const Eigen::MatrixXd modes = RigidMotions(moved);
  for (int m = 0; m < 6; ++m) {
    EXPECT_LT((k * modes.col(m)).norm(), 1e-12 * k_norm * modes.col(m).norm()) << "mode " << m;
  }
}

TEST(Stiffness, MatrixFreeProductMatchesTheAssembledMatrix) {
  const glm::dvec3 extent(10.0, 12.0, 8.0);
  const ProxyMesh mesh = RandomBoxMesh(30, 3, extent, 9);
  const auto elements = Elements(mesh);
  const auto n = static_cast<int64_t>(mesh.vertices.size());
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd u(3 * n), v(3 * n);
  for (int64_t i = 0; i < 3 * n; ++i) u[i] = 0.8 * g(rng), v[i] = g(rng);
  for (FemMethod method : {FemMethod::kCorotational, FemMethod::kCorotationalConsistent}) {
    CorotatedFrames frames;
    Eigen::VectorXd forces, product;
    CorotatedForces(elements, u, method, frames, forces);
    ApplyCorotatedStiffness(elements, frames, v, product);
    const Eigen::VectorXd assembled = AssembleStiffness(elements, frames, n) * v;
    EXPECT_LT((product - assembled).norm(), 1e-13 * assembled.norm());
    // Symmetric positive semi-definite at any state (the twist term clamped).
    const Eigen::MatrixXd dense(AssembleStiffness(elements, frames, n));
    EXPECT_LT((dense - dense.transpose()).norm(), 1e-13 * dense.norm());
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
    EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-12 * eig.eigenvalues().maxCoeff());
    // Split over threads: the same up to the order of the sums.
    CorotatedFrames frames2;
    Eigen::VectorXd forces2, product2;
    CorotatedForces(elements, u, method, frames2, forces2, /*threads=*/3);
    ApplyCorotatedStiffness(elements, frames2, v, product2, /*threads=*/2);
    EXPECT_LT((forces2 - forces).norm(), 1e-14 * forces.norm());
    EXPECT_LT((product2 - product).norm(), 1e-14 * product.norm());
  }
}

TEST(Stiffness, CorotatedForcesAreTheGradientOfTheEnergy) {
  const glm::dvec3 extent(10.0, 12.0, 8.0);
  const ProxyMesh mesh = RandomBoxMesh(20, 2, extent, 4);
  const auto elements = Elements(mesh);
  const auto n = static_cast<int64_t>(mesh.vertices.size());
  std::mt19937 rng(6);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd u(3 * n);
  for (int64_t i = 0; i < 3 * n; ++i) u[i] = 0.5 * g(rng);
  CorotatedFrames frames;
  Eigen::VectorXd forces, unused;
  CorotatedForces(elements, u, FemMethod::kCorotational, frames, forces);
  auto energy = [&](const Eigen::VectorXd& w) {
    CorotatedFrames f;
    CorotatedForces(elements, w, FemMethod::kCorotational, f, unused);
    return CorotatedEnergy(elements, f.rotations, w);
  };
  const double step = 1e-5;
  for (int64_t i = 0; i < 3 * n; i += 7) {
    Eigen::VectorXd plus = u, minus = u;
    plus[i] += step;
    minus[i] -= step;
    const double numeric = (energy(plus) - energy(minus)) / (2.0 * step);
    EXPECT_NEAR(forces[i], numeric, 1e-6 * forces.cwiseAbs().maxCoeff()) << "dof " << i;
  }
}

// In tension (where no clamping happens) the consistent tangent is the exact
// derivative of the forces; the frozen-rotation tangent R K0 R^T is not.
TEST(Stiffness, ConsistentTangentIsTheForceDerivativeInTension) {
  const glm::dvec3 extent(10.0, 12.0, 8.0);
  const ProxyMesh mesh = RandomBoxMesh(20, 2, extent, 5);
  const auto elements = Elements(mesh);
  const auto rest = RestPositions(mesh);
  const auto n = static_cast<int64_t>(rest.size());
  const Eigen::Matrix3d a =
      Rotation(Eigen::Vector3d(0.3, 1.0, -0.4), 0.7) * Eigen::Vector3d(1.2, 1.1, 1.3).asDiagonal();
  std::mt19937 rng(8);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd u(3 * n), v(3 * n);
  for (int64_t p = 0; p < n; ++p) {
    const Eigen::Vector3d x(rest[p].x, rest[p].y, rest[p].z);
    u.segment<3>(3 * p) = a * x - x;
  }
  for (int64_t i = 0; i < 3 * n; ++i) v[i] = g(rng);
  auto forces_at = [&](const Eigen::VectorXd& w) {
    CorotatedFrames f;
    Eigen::VectorXd out;
    CorotatedForces(elements, w, FemMethod::kCorotational, f, out);
    return out;
  };
  const double step = 1e-6;
  const Eigen::VectorXd numeric = (forces_at(u + step * v) - forces_at(u - step * v)) / (2 * step);
  for (FemMethod method : {FemMethod::kCorotationalConsistent, FemMethod::kCorotational}) {
    CorotatedFrames frames;
    Eigen::VectorXd forces, product;
    CorotatedForces(elements, u, method, frames, forces);
    ApplyCorotatedStiffness(elements, frames, v, product);
    const double error = (product - numeric).norm() / numeric.norm();
    if (method == FemMethod::kCorotationalConsistent) {
      EXPECT_LT(error, 1e-6);
    } else {
      EXPECT_GT(error, 1e-2);
    }
  }
}

}  // namespace
}  // namespace vpm

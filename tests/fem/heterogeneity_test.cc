// Material heterogeneity: a hard inclusion (E_hard = 1e4 E_soft) in a
// stretched soft cube barely deforms; hard vertices of a proxy mesh do not
// move and make their tets hard.
#include <cmath>

#include <gtest/gtest.h>

#include "server/fem/corotated_forces.h"
#include "server/fem/corotational_solver.h"
#include "server/fem/fem_model.h"
#include "server/fem/fem_units.h"
#include "tests/fem/fem_test_meshes.h"

namespace vpm {
namespace {

using testing::GridMesh;
using testing::RestPositions;

TEST(Heterogeneity, HardInclusionBarelyDeforms) {
  const double side = 20.0;
  const ProxyMesh mesh = GridMesh({8, 8, 8}, glm::dvec3(side));
  const auto rest = RestPositions(mesh);
  const double soft = KpaToNPerMm2(5.0);
  std::vector<double> moduli(mesh.tets.size(), soft);
  std::vector<uint8_t> inclusion(mesh.tets.size(), 0);
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    glm::dvec3 centroid(0.0);
    for (int32_t v : mesh.tets[t]) centroid += rest[v] / 4.0;
    const glm::dvec3 d = glm::abs(centroid - glm::dvec3(side / 2));
    inclusion[t] = d.x < 2.5 && d.y < 2.5 && d.z < 2.5;
    if (inclusion[t]) moduli[t] = 1e4 * soft;
  }
  // Lateral faces slide, the bottom slides on z = 0, the top is pulled up by
  // 10% of the side (prescribed), with a shear to make it less symmetric.
  std::vector<uint8_t> fixed(3 * rest.size(), 0);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(3 * rest.size());
  for (size_t v = 0; v < rest.size(); ++v) {
    for (int i = 0; i < 2; ++i) {
      if (rest[v][i] == 0.0 || rest[v][i] == side) fixed[3 * v + i] = 1;
    }
    if (rest[v].z == 0.0 || rest[v].z == side) fixed[3 * v + 2] = 1;
    if (rest[v].z == side) prescribed[3 * v + 2] = 0.1 * side;
  }
  auto solver = CorotationalSolver::Create(rest, mesh.tets, moduli, 0.45, fixed);
  ASSERT_TRUE(solver.ok()) << solver.status();
  auto stats =
      solver->Solve(prescribed, Eigen::VectorXd::Zero(prescribed.size()), HandleMode::kPrescribed);
  ASSERT_TRUE(stats.ok());
  EXPECT_TRUE(stats->converged);
  const std::vector<Eigen::Matrix3d>& rotations = solver->frames().rotations;
  double hard_max = 0.0, soft_sum = 0.0;
  int soft_count = 0;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const TetElement& e = solver->elements()[t];
    Eigen::Matrix<double, 3, 4> u;
    for (int a = 0; a < 4; ++a) u.col(a) = solver->displacement_mm().segment<3>(3 * e.vertices[a]);
    const Eigen::Matrix3d h =
        rotations[t].transpose() * (Eigen::Matrix3d::Identity() + DisplacementGradient(e, u)) -
        Eigen::Matrix3d::Identity();
    const double strain = (0.5 * (h + h.transpose())).norm();
    if (inclusion[t]) {
      hard_max = std::max(hard_max, strain);
    } else {
      soft_sum += strain, ++soft_count;
    }
  }
  const double soft_mean = soft_sum / soft_count;
  std::printf("strain: soft mean %.3e, inclusion max %.3e (ratio %.1e)\n", soft_mean, hard_max,
              hard_max / soft_mean);
  EXPECT_GT(soft_mean, 0.05);
  EXPECT_LT(hard_max, 1e-2 * soft_mean);
}

TEST(Heterogeneity, HardVerticesStayPutAndHardenTheirTets) {
  const glm::dvec3 extent(30.0);
  ProxyMesh mesh = GridMesh({6, 6, 6}, extent);
  int hard = 0;
  for (MeshVertex& v : mesh.vertices) {
    const glm::dvec3 d = v.position_mm - glm::dvec3(10.0, 15.0, 15.0);
    if (glm::length(d) < 5.5) v.hard = v.skeleton = true, ++hard;
  }
  ASSERT_GT(hard, 3);
  auto model = FemModel::Create(mesh, extent);
  ASSERT_TRUE(model.ok()) << model.status();
  int64_t touching = 0;
  for (const auto& tet : mesh.tets) {
    bool any = false;
    for (int32_t v : tet) any = any || mesh.vertices[v].hard;
    touching += any;
  }
  EXPECT_EQ(model->setup().hard_tets, touching);
  const auto grab = model->Grab(glm::dvec3(17.5, 15.0, 15.0), 3.0);
  ASSERT_TRUE(grab.ok()) << grab.status();
  EXPECT_EQ(grab->handles.size(), 1u);
  EXPECT_EQ(grab->fixed_within, 1);  // the hard vertex at (15, 15, 15)
  EXPECT_NE(grab->message.find("fixed"), std::string::npos) << grab->message;
  auto stats = model->Drag(glm::dvec3(3.0, 0.0, 0.0));
  ASSERT_TRUE(stats.ok()) << stats.status();
  const auto u = model->Displacements();
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (mesh.vertices[v].hard) {
      EXPECT_EQ(u[v], glm::dvec3(0.0)) << v;
    }
  }
  EXPECT_EQ(model->CountInvertedTets(), 0);
}

}  // namespace
}  // namespace vpm

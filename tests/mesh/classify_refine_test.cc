#include <gtest/gtest.h>

#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/classify_hardness.h"
#include "server/mesh/point_grid.h"
#include "server/mesh/refine_at_point.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

// A 1D row of vertices over a volume whose values we set per voxel, and one
// voxel of air (-1000 HU) after them with no vertex: CT in HU (ct_in_hu.h),
// so that the HU rules apply.
struct Row {
  Volume volume;
  std::vector<MeshVertex> vertices;
};

Row MakeRow(std::vector<float> values) {
  const int64_t n = static_cast<int64_t>(values.size());
  values.push_back(-1000.0f);
  VolumeGeometry g;
  g.dims = {n + 1, 1, 1};
  Row row{*Volume::Create(g, values), {}};
  for (int64_t i = 0; i < n; ++i) {
    row.vertices.push_back({.position_mm = glm::dvec3(i, 0, 0), .lattice_id = i, .voxel = {i, 0, 0}});
  }
  return row;
}

TEST(ClassifyHardness, BoneThresholdAndOnePassInfluence) {
  // bone at 0; 1 and 2 above the influence threshold; with R = 2 the
  // influence radius is 1.5: vertex 1 is influenced, vertex 2 is not even
  // though it touches 1 (not transitive); 3 is too soft.
  Row row = MakeRow({700, 150, 150, 50, 260});
  ASSERT_TRUE(ClassifyHardness(row.volume, 2.0, {}, row.vertices).ok());
  std::vector<bool> hard;
  for (const auto& v : row.vertices) hard.push_back(v.hard);
  EXPECT_EQ(hard, (std::vector<bool>{true, true, false, false, true}));
}

TEST(ClassifyHardness, OverridesWinInOrder) {
  Row row = MakeRow({700, 150, 150, 50, 260});
  ClassifyParams p;
  p.overrides.push_back({.shape = HardnessOverride::Shape::kIds, .hard = false, .ids = {0}});
  p.overrides.push_back({.shape = HardnessOverride::Shape::kSphere, .hard = true,
                         .center_mm = {3, 0, 0}, .radius_mm = 0.5});
  p.overrides.push_back({.shape = HardnessOverride::Shape::kBox, .hard = false,
                         .box_min_mm = {3.5, -1, -1}, .box_max_mm = {5, 1, 1}});
  ASSERT_TRUE(ClassifyHardness(row.volume, 2.0, p, row.vertices).ok());
  EXPECT_FALSE(row.vertices[0].hard);
  EXPECT_TRUE(row.vertices[3].hard);
  EXPECT_FALSE(row.vertices[4].hard);
  p.overrides = {{.shape = HardnessOverride::Shape::kIds, .ids = {99}}};
  EXPECT_EQ(ClassifyHardness(row.volume, 2.0, p, row.vertices).code(),
            absl::StatusCode::kNotFound);
}

class RefineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    MeshParams params;
    params.grid = {12, 10, 8};
    params.target = 100;
    auto base = DecimateLattice(volume_, params);
    ASSERT_TRUE(base.ok()) << base.status();
    base_.emplace(std::move(*base));
  }
  Result<std::vector<MeshVertex>> Refine(glm::dvec3 m, int64_t count = 150) {
    return RefineAtPoint(volume_, base_->lattice, base_->tf, base_->g_max, base_->vertices,
                         {.point_mm = m, .roi_radius_mm = 1.5 * base_->lattice.h_mm(),
                          .refine_count = count});
  }
  Volume volume_ = testing::MakeBodyVolume();
  std::optional<DecimatedLattice> base_;
};

TEST_F(RefineTest, AcceptsOnlyWellSeparatedCandidatesInTheBall) {
  const glm::dvec3 m = volume_.geometry().extent_mm() * 0.5;
  auto refined = Refine(m);
  ASSERT_TRUE(refined.ok()) << refined.status();
  ASSERT_FALSE(refined->empty());
  const double h = base_->lattice.h_mm();
  std::vector<glm::dvec3> all;
  for (const auto& v : base_->vertices) all.push_back(v.position_mm);
  for (const auto& v : *refined) {
    EXPECT_EQ(v.kind, VertexKind::kRefined);
    EXPECT_EQ(v.lattice_id, -1);
    EXPECT_LE(PointDistance(v.position_mm, m), 1.5 * h + 1e-9);
    for (const auto& q : all) EXPECT_GE(PointDistance(v.position_mm, q), h / 3.0 - 1e-12);
    all.push_back(v.position_mm);
  }
  for (size_t n = 1; n < refined->size(); ++n) EXPECT_GE((*refined)[n - 1].cost, (*refined)[n].cost);
  auto capped = Refine(m, 3);
  ASSERT_TRUE(capped.ok());
  EXPECT_EQ(capped->size(), std::min<size_t>(3, refined->size()));
}

TEST_F(RefineTest, RejectsPointsOutsideTheVolume) {
  EXPECT_EQ(Refine({-1.0, 5.0, 5.0}).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(Refine(volume_.geometry().extent_mm() + 0.1).status().code(),
            absl::StatusCode::kOutOfRange);
  EXPECT_EQ(Refine({std::nan(""), 5.0, 5.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_F(RefineTest, NewPointReplacesThePreviousRefinement) {
  MeshParams params;
  params.grid = {12, 10, 8};
  params.target = 100;
  params.refine_at_mm = volume_.geometry().extent_mm() * 0.3;
  auto first = FinishProxyMesh(volume_, *base_, params);
  params.refine_at_mm = volume_.geometry().extent_mm() * 0.7;
  auto second = FinishProxyMesh(volume_, *base_, params);
  ASSERT_TRUE(first.ok() && second.ok()) << first.status() << second.status();
  auto count_refined = [](const ProxyMesh& m) {
    return std::count_if(m.vertices.begin(), m.vertices.end(),
                         [](const MeshVertex& v) { return v.kind == VertexKind::kRefined; });
  };
  EXPECT_EQ(count_refined(*second), second->stats.refined);
  // Steiner points (slivers; long hard-soft edges near the refinement point)
  // come on top of the refined and boundary vertices.
  EXPECT_EQ(second->vertices.size(), base_->vertices.size() + second->stats.refined +
                                         second->stats.boundary + second->stats.steiner);
  for (const auto& v : second->vertices) {
    if (v.kind == VertexKind::kRefined) {
      EXPECT_LE(PointDistance(v.position_mm, *params.refine_at_mm), 1.5 * base_->stats.h_mm + 1e-9);
    }
  }
  EXPECT_GT(count_refined(*first), 0);
}

// A stack of fewer slices than three times the lattice (thick-slice CT, most
// MR series: 16 slices of 6 mm under a lattice of 8 along z): the candidates'
// lattice is as fine as the slices there, and the refinement is made.
TEST(RefineAtPoint, AStackThinnerThanThreeLatticesIsRefinedAtItsSlices) {
  const Volume volume = testing::MakeBodyVolume({48, 40, 16}, {1.0, 1.2, 6.0});
  MeshParams params;
  params.grid = {12, 10, 8};
  params.target = 100;
  auto base = DecimateLattice(volume, params);
  ASSERT_TRUE(base.ok()) << base.status();
  const glm::dvec3 m = volume.geometry().extent_mm() * 0.5;
  auto refined = RefineAtPoint(
      volume, base->lattice, base->tf, base->g_max, base->vertices,
      {.point_mm = m, .roi_radius_mm = 1.5 * base->lattice.h_mm(), .refine_count = 150});
  ASSERT_TRUE(refined.ok()) << refined.status();
  EXPECT_FALSE(refined->empty());
  for (const auto& v : *refined) {
    EXPECT_LE(PointDistance(v.position_mm, m), 1.5 * base->lattice.h_mm() + 1e-9);
  }
}

TEST(BuildProxyMesh, KeepsTargetAnchorsAndTetsCoverTheBox) {
  const Volume volume = testing::MakeBodyVolume();
  MeshParams params;
  params.grid = {12, 10, 8};
  params.target = 100;
  auto mesh = BuildProxyMesh(volume, params);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  // The target counts steps 1-4; the boundary vertices come on top.
  EXPECT_EQ(mesh->vertices.size(), 100u + mesh->stats.boundary);
  EXPECT_EQ(std::count_if(mesh->vertices.begin(), mesh->vertices.end(),
                          [](const MeshVertex& v) { return v.kind == VertexKind::kBoundary; }),
            mesh->stats.boundary);
  EXPECT_EQ(mesh->stats.anchors, 8);
  EXPECT_EQ(mesh->stats.kept_lattice, 92);
  EXPECT_GT(mesh->stats.hard, 0);  // the bone rod
  EXPECT_GT(mesh->tets.size(), 100u);
  EXPECT_EQ(mesh->stats.tets, static_cast<int64_t>(mesh->tets.size()));
}

}  // namespace
}  // namespace vpm

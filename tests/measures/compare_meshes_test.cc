// Section 6 on the built-in phantom: what the optimized mesh buys over a
// regular lattice of the same budget, and which density mode is better.
#include "server/measures/compare_meshes.h"

#include <gtest/gtest.h>

#include "server/phantom/phantom.h"

namespace vpm {
namespace {

const MeshComparisonRow& Row(const std::vector<MeshComparisonRow>& rows, const std::string& name) {
  for (const auto& r : rows) {
    if (r.name == name) return r;
  }
  ADD_FAILURE() << "no row " << name;
  return rows.front();
}

class CompareMeshesOnPhantom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto volume = MakePhantom("abdomen", VolumeLimits{});
    ASSERT_TRUE(volume.ok()) << volume.status();
    auto rows = CompareMeshes(*volume, MeshParams{});  // the defaults: 20^3 -> 250, cell, spread
    ASSERT_TRUE(rows.ok()) << rows.status();
    rows_ = new std::vector<MeshComparisonRow>(std::move(*rows));
    for (const auto& r : *rows_) {
      std::printf("%-13s RMSE all %7.2f  TF>0 %7.2f  empty sphere %7.2f mm\n", r.name.c_str(),
                  r.reconstruction.rmse_all, r.reconstruction.rmse_tf_positive,
                  r.largest_empty_sphere.radius_mm);
    }
  }
  static void TearDownTestSuite() { delete rows_; }
  static std::vector<MeshComparisonRow>* rows_;
};
std::vector<MeshComparisonRow>* CompareMeshesOnPhantom::rows_ = nullptr;

TEST_F(CompareMeshesOnPhantom, EveryMeshHasTheSameBudgetAndCoversTheBox) {
  for (const auto& r : *rows_) {
    // The budget counts steps 1-4; boundary and Steiner vertices come on top.
    EXPECT_LE(r.vertices - r.boundary_vertices - r.steiner_vertices, 250) << r.name;
    EXPECT_GE(r.vertices - r.boundary_vertices - r.steiner_vertices, 240) << r.name;
    EXPECT_EQ(r.reconstruction.voxels_outside_mesh, 0) << r.name;
  }
}

const MeshComparisonRow& DefaultRow(const std::vector<MeshComparisonRow>& rows) {
  for (const auto& r : rows) {
    if (r.is_default) return r;
  }
  ADD_FAILURE() << "no row is marked default";
  return rows.front();
}

TEST_F(CompareMeshesOnPhantom, DefaultBeatsTheRegularLatticeOnTissueRmse) {
  EXPECT_LT(DefaultRow(*rows_).reconstruction.rmse_tf_positive,
            Row(*rows_, "regular").reconstruction.rmse_tf_positive);
}

// Why point is to become the default footprint (docs/ALGORITHM.md section
// 1): on the phantom it reconstructs the tissue better than cell at the same
// budget.
TEST_F(CompareMeshesOnPhantom, PointFootprintBeatsCellOnTissueRmse) {
  EXPECT_LT(Row(*rows_, "point/spread").reconstruction.rmse_tf_positive,
            Row(*rows_, "cell/spread").reconstruction.rmse_tf_positive);
}

TEST_F(CompareMeshesOnPhantom, SpreadModeBeatsPaperModeOnTissueRmse) {
  // The default density mode must be the better one (section 6, "Spread").
  EXPECT_LT(Row(*rows_, "cell/spread").reconstruction.rmse_tf_positive,
            Row(*rows_, "cell/paper").reconstruction.rmse_tf_positive);
  EXPECT_LT(Row(*rows_, "point/spread").reconstruction.rmse_tf_positive,
            Row(*rows_, "point/paper").reconstruction.rmse_tf_positive);
}

}  // namespace
}  // namespace vpm

// Section 6 deformation measures on the phantom (docs/ALGORITHM.md): error of the
// standard drag against the dense-lattice reference, rigidity of bone, and
// validity of the mesh after drags up to 1.5 h.
#include "server/measures/deformation_measures.h"

#include <cmath>

#include <gtest/gtest.h>

#include "server/phantom/phantom.h"

namespace vpm {
namespace {

class DeformationOnPhantom : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // 128^3 keeps the voxel sampling quick; the mesh and FEM do not depend on it.
    auto volume = MakePhantom("abdomen?size=128", VolumeLimits{});
    ASSERT_TRUE(volume.ok()) << volume.status();
    auto rows = CompareDeformation(*volume, MeshParams{}, StandardDrag{});
    ASSERT_TRUE(rows.ok()) << rows.status();
    rows_ = new std::vector<DeformationMeasure>(std::move(*rows));
    for (const auto& r : *rows_) {
      std::printf(
          "%-9s verts %5lld handles %3lld RMS %.3f mm max %.3f mm bone %.2f%% at "
          "(%.0f, %.0f, %.0f) mm, inverted %lld / %lld at 1.5h\n",
          r.name.c_str(), (long long)r.vertices, (long long)r.handles, r.rms_error_mm,
          r.max_error_mm, 100 * r.bone_max_fraction, r.bone_worst_mm.x, r.bone_worst_mm.y,
          r.bone_worst_mm.z, (long long)r.inverted_at_drag, (long long)r.inverted_at_1_5h);
    }
  }
  static void TearDownTestSuite() { delete rows_; }
  static const DeformationMeasure& Row(const std::string& name) {
    for (const auto& r : *rows_) {
      if (r.name == name) return r;
    }
    ADD_FAILURE() << name;
    return rows_->front();
  }
  static std::vector<DeformationMeasure>* rows_;
};
std::vector<DeformationMeasure>* DeformationOnPhantom::rows_ = nullptr;

// What section 6 expects, on the standard drag (docs/MESH.md): step 4 beats
// step 2, step 2 beats the regular lattice, and bone moves under 5% of the
// drag on the step-4 mesh. Validity: with the inversion barrier no tet
// inverts after the drag or after 1.5 h, except where the prescribed drag
// flattens a tet by itself (the step-2 mesh: two handles and a hard vertex in
// one tet; docs/FEM.md), which the row must then report as forced.
// One test (one process under ctest): the dense reference solve dominates.
TEST_F(DeformationOnPhantom, Step4BeatsStep2BeatsRegularAndBoneStaysRigid) {
  EXPECT_LT(Row("step 4").rms_error_mm, Row("step 2").rms_error_mm);
  EXPECT_LT(Row("step 2").rms_error_mm, Row("regular").rms_error_mm);
  EXPECT_LT(Row("step 4").bone_max_fraction, 0.05);
  EXPECT_LT(Row("reference").bone_max_fraction, 0.05);
  EXPECT_EQ(Row("reference").inverted_at_drag, 0);
  EXPECT_EQ(Row("reference").inverted_at_1_5h, 0);
  EXPECT_EQ(Row("regular").inverted_at_drag, 0);
  EXPECT_EQ(Row("regular").inverted_at_1_5h, 0);
  EXPECT_EQ(Row("step 4").inverted_at_drag, 0);
  EXPECT_EQ(Row("step 4").inverted_at_1_5h, 0);
  for (const auto& r : *rows_) {
    EXPECT_TRUE(r.inverted_at_drag == 0 || r.forced_at_drag) << r.name;
    EXPECT_TRUE(r.inverted_at_1_5h == 0 || r.forced_at_1_5h) << r.name;
    EXPECT_TRUE(r.converged) << r.name;
    EXPECT_GT(r.handles, 0) << r.name;
    EXPECT_TRUE(std::isfinite(r.rms_error_mm)) << r.name;
  }
}

}  // namespace
}  // namespace vpm

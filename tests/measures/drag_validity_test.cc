// Issue 16's valid meshes on real data (docs/ALGORITHM.md sections 5-6): on
// meshes refined at the grab point as the server builds them, no tet under
// 5 degrees, and no inverted tet after drags of 0.5 h, 1 h and 1.5 h in the
// interactive FEM settings (10 increments, as a user drags) and the measuring
// ones; bench/mesh_validity_bench.cc prints the same table.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/fem/fem_model.h"
#include "server/io/read_volume.h"
#include "server/measures/deformation_measures.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/phantom/phantom.h"

namespace vpm {
namespace {

// Builds the mesh refined at `grab_mm` as the server does and expects every
// tet at 5 degrees or more (Steiner points, docs/MESH.md); then grabs the
// vertices within h/2 of `grab_mm` and drags them anteriorly (-y) by each
// fraction of h up to `max_fraction`, from rest, in both FEM settings:
// interactive (SolverOptions defaults, 10 increments, as a user drags) and
// measuring (MeasurementFemOptions, one Drag call); expects every tet
// positive and no forced inversion.
void ExpectValidMeshAndDrags(const Volume& volume, const std::string& tf, Footprint footprint,
                             const glm::dvec3& grab_mm, double max_fraction = 1.5) {
  MeshParams params;
  params.footprint = footprint;
  params.tf = tf;
  params.refine_at_mm = grab_mm;
  // Refinement needs 3G voxels per axis: thin volumes get a coarser G there.
  for (int a = 0; a < 3; ++a) {
    params.grid[a] = std::min<int64_t>(params.grid[a], volume.geometry().dims[a] / 3);
  }
  auto mesh = BuildProxyMesh(volume, params);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  EXPECT_GE(mesh->quality.min_dihedral_deg, 5.0) << FootprintName(footprint);
  const double h = mesh->stats.h_mm;
  const FemOptions interactive;
  const FemOptions measuring = MeasurementFemOptions();
  for (const FemOptions* options : {&interactive, &measuring}) {
    const int increments = options == &interactive ? 10 : 1;
    for (double fraction : {0.5, 1.0, 1.5}) {
      if (fraction > max_fraction) continue;
      SCOPED_TRACE(StrCat(FootprintName(footprint), options == &interactive ? ", interactive" : ", measuring",
                          ", drag ", fraction, " h"));
      auto model = FemModel::Create(*mesh, volume.geometry().extent_mm(), *options);
      ASSERT_TRUE(model.ok()) << model.status();
      ASSERT_TRUE(model->Grab(grab_mm, 0.5 * h).ok());
      const glm::dvec3 drag(0.0, -fraction * h, 0.0);
      for (int i = 1; i <= increments; ++i) {
        const auto stats = model->Drag(drag * (static_cast<double>(i) / increments));
        ASSERT_TRUE(stats.ok()) << stats.status();
        EXPECT_FALSE(stats->forced_inversion) << "increment " << i;
      }
      EXPECT_EQ(model->CountInvertedTets(), 0);
    }
  }
}

// One test per volume and footprint, so that each stays a few seconds.
void PhantomStandardDrag(Footprint footprint) {
  auto volume = MakePhantom("abdomen?size=128", VolumeLimits{});
  ASSERT_TRUE(volume.ok()) << volume.status();
  glm::dvec3 grab(0.0);
  for (const Landmark& l : volume->landmarks()) {
    if (l.name == StandardDrag{}.landmark) grab = l.position_mm;
  }
  ExpectValidMeshAndDrags(*volume, "ct-soft-tissue", footprint, grab);
}

TEST(DragValidity, PhantomPointMeshHasNoSliverAndStandardDragPointsInvertNoTet) {
  PhantomStandardDrag(Footprint::kPoint);
}

TEST(DragValidity, PhantomCellMeshHasNoSliverAndStandardDragPointsInvertNoTet) {
  PhantomStandardDrag(Footprint::kCell);
}

// Debian's mricron-data (scripts/install-deps.sh) ships the Colin27 T1
// average; grabbed at the centre of its box (inside the brain).
void ColinCentreDrags(Footprint footprint) {
  const std::string colin = "/usr/share/mricron/templates/ch2.nii.gz";
  ASSERT_TRUE(std::filesystem::exists(colin)) << "install mricron-data (scripts/install-deps.sh)";
  auto volume = ReadVolume(colin, VolumeLimits{});
  ASSERT_TRUE(volume.ok()) << volume.status();
  ExpectValidMeshAndDrags(*volume, "mri-t1", footprint, volume->geometry().extent_mm() * 0.5);
}

TEST(DragValidity, ColinMriPointMeshHasNoSliverAndCentreDragsInvertNoTet) {
  ColinCentreDrags(Footprint::kPoint);
}

TEST(DragValidity, ColinMriCellMeshHasNoSliverAndCentreDragsInvertNoTet) {
  ColinCentreDrags(Footprint::kCell);
}

// The real gantry-tilted head CT in the repository (tests/data/ct-philips-tilt,
// 54 slices after resampling, so G = 20 x 20 x 18 as the benchmark takes
// it), grabbed at the centre of its box (inside the brain). Up to 1.5 h only
// since the Steiner points on long hard edges (hard_reach_steiner_points.h):
// before them hard tets from the skull held brain vertices 10 mm from the
// grab still, and the 1.5 h drags ended with 11-25 tets forced inverted
// (docs/FEM.md, "Forced inversions").
Result<Volume> TiltedCt() {
  const char* root = std::getenv("VPM_SOURCE_DIR");
  const std::string folder = std::string(root ? root : ".") + "/tests/data/ct-philips-tilt";
  if (!std::filesystem::exists(folder)) return absl::NotFoundError(folder);
  return ReadVolume(folder, VolumeLimits{});
}

void TiltedCtCentreDrags(Footprint footprint) {
  auto volume = TiltedCt();
  ASSERT_TRUE(volume.ok()) << volume.status();
  ExpectValidMeshAndDrags(*volume, "ct-soft-tissue", footprint,
                          volume->geometry().extent_mm() * 0.5);
}

TEST(DragValidity, TiltedHeadCtPointMeshHasNoSliverAndCentreDragsInvertNoTet) {
  TiltedCtCentreDrags(Footprint::kPoint);
}

TEST(DragValidity, TiltedHeadCtCellMeshHasNoSliverAndCentreDragsInvertNoTet) {
  TiltedCtCentreDrags(Footprint::kCell);
}

// What the tests above guard against: the same mesh without the Steiner
// points on long hard edges (MeshParams::hard_reach_factor = 0) still
// forces inversions in the 1.5 h interactive drag, and in the tets around
// the grab; if this stops failing, the tests above no longer show that the
// points are what makes the drag valid.
TEST(DragValidity, TiltedHeadCtWithoutHardReachPointsForcesInversionsAtOneAndAHalfH) {
  auto volume = TiltedCt();
  ASSERT_TRUE(volume.ok()) << volume.status();
  MeshParams params;
  params.refine_at_mm = volume->geometry().extent_mm() * 0.5;
  for (int a = 0; a < 3; ++a) {
    params.grid[a] = std::min<int64_t>(params.grid[a], volume->geometry().dims[a] / 3);
  }
  params.hard_reach_factor = 0.0;
  auto mesh = BuildProxyMesh(*volume, params);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  const double h = mesh->stats.h_mm;
  auto model = FemModel::Create(*mesh, volume->geometry().extent_mm());
  ASSERT_TRUE(model.ok()) << model.status();
  ASSERT_TRUE(model->Grab(*params.refine_at_mm, 0.5 * h).ok());
  bool forced = false;
  for (int i = 1; i <= 10; ++i) {
    const auto stats = model->Drag(glm::dvec3(0.0, -1.5 * h * i / 10.0, 0.0));
    ASSERT_TRUE(stats.ok()) << stats.status();
    forced |= stats->forced_inversion;
  }
  EXPECT_TRUE(forced);
  EXPECT_GT(model->CountInvertedTets(), 0);
}

// Where each landmark is, mm; the box centre when the volume has none.
glm::dvec3 LandmarkOrCentre(const Volume& volume, const std::string& name) {
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == name) return l.position_mm;
  }
  return volume.geometry().extent_mm() * 0.5;
}

// A 12 mm drag as `vpm render --grab... --drag` takes it (grab radius h, one
// Drag call, interactive settings) on a point-footprint mesh refined at the
// grab: the handles move exactly 12 mm, nothing moves more than 10% further
// (the tissue around may bulge a little; forced_drag_test.cc allows 25% for
// a forced step) and no tet inverts.
void ExpectTwelveMmDragStaysBounded(const Volume& volume, MeshParams params,
                                    const glm::dvec3& grab_mm) {
  params.footprint = Footprint::kPoint;
  params.refine_at_mm = grab_mm;
  auto mesh = BuildProxyMesh(volume, params);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  auto model = FemModel::Create(*mesh, volume.geometry().extent_mm());
  ASSERT_TRUE(model.ok()) << model.status();
  auto grab = model->Grab(grab_mm, mesh->stats.h_mm);
  ASSERT_TRUE(grab.ok()) << grab.status();
  const glm::dvec3 drag(0.0, 0.0, 12.0);
  const auto stats = model->Drag(drag);
  ASSERT_TRUE(stats.ok()) << stats.status();
  const std::vector<glm::dvec3> u = model->Displacements();
  double max_mm = 0.0;
  for (const glm::dvec3& d : u) max_mm = std::max(max_mm, glm::length(d));
  for (int32_t h : grab->handles) EXPECT_NEAR(glm::distance(u[h], drag), 0.0, 1e-9);
  EXPECT_LE(max_mm, 1.1 * 12.0) << grab->message;
  EXPECT_EQ(model->CountInvertedTets(), 0) << grab->message;
  EXPECT_FALSE(stats->forced_inversion);
}

// The service process test's case (tests/service/service_process_test.sh):
// with the point footprint the artery's contrast makes hard vertices inside
// the grab ball; when the grab took the soft vertices beside them as handles
// this drag threw a vertex 27.3 mm and inverted 7 tets (docs/FEM.md,
// "Manipulation").
TEST(DragValidity, SmallPhantomPointMeshTwelveMmDragMovesNothingPastTheDrag) {
  auto volume = MakePhantom("abdomen?size=48", VolumeLimits{});
  ASSERT_TRUE(volume.ok()) << volume.status();
  MeshParams params;
  params.grid = {10, 10, 10};
  params.target = 60;
  ExpectTwelveMmDragStaysBounded(*volume, params,
                                 LandmarkOrCentre(*volume, "left_renal_artery"));
}

TEST(DragValidity, ColinMriPointMeshTwelveMmDragMovesNothingPastTheDrag) {
  const std::string colin = "/usr/share/mricron/templates/ch2.nii.gz";
  ASSERT_TRUE(std::filesystem::exists(colin)) << "install mricron-data (scripts/install-deps.sh)";
  auto volume = ReadVolume(colin, VolumeLimits{});
  ASSERT_TRUE(volume.ok()) << volume.status();
  MeshParams params;
  params.tf = "mri-t1";
  ExpectTwelveMmDragStaysBounded(*volume, params, volume->geometry().extent_mm() * 0.5);
}

}  // namespace
}  // namespace vpm

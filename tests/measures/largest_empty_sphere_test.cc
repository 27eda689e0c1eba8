// Section 6 "Spread": the largest empty sphere inside the body.
#include "server/measures/largest_empty_sphere.h"

#include <cmath>

#include <gtest/gtest.h>

#include "server/volume/sample_trilinear.h"
#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm {
namespace {

using testing::LatticeMesh;
using testing::MakeVolume;

// 41^3 voxels of 1 mm: box 40 mm; G = 5 gives cells of d = 8 mm.
constexpr double kCellMm = 8.0;

Volume Uniform(float value) {
  return MakeVolume({41, 41, 41}, {1.0, 1.0, 1.0},
                    [value](int64_t, int64_t, int64_t) { return value; });
}

ProxyMesh VolumeLatticeMesh(const Volume& volume, const std::function<bool(int, int, int)>& keep = nullptr) {
  const glm::dvec3 extent = volume.geometry().extent_mm();
  ProxyMesh mesh = LatticeMesh(5, extent, keep);
  EXPECT_TRUE(Tetrahedralize(mesh, extent).ok());
  return mesh;
}

const TransferFunction& PositiveAbove50() {
  static const TransferFunction tf = *TransferFunction::Create({{50.0, 0.0}, {60.0, 1.0}});
  return tf;
}

TEST(LargestEmptySphere, FullLatticeGivesHalfTheCellDiagonal) {
  const Volume volume = Uniform(100.0f);
  const ProxyMesh mesh = VolumeLatticeMesh(volume);
  auto sphere = LargestEmptySphere(mesh, volume, PositiveAbove50());
  ASSERT_TRUE(sphere.ok()) << sphere.status();
  EXPECT_NEAR(sphere->radius_mm, kCellMm * std::sqrt(3.0) / 2.0, 1e-9);
  EXPECT_GT(sphere->circumcentres_in_body, 0);
  EXPECT_FALSE(sphere->centre_is_sample);
  // Boundary samples find nothing larger on a full lattice.
  auto sampled = LargestEmptySphere(mesh, volume, PositiveAbove50(), {1});
  ASSERT_TRUE(sampled.ok());
  EXPECT_NEAR(sampled->radius_mm, sphere->radius_mm, 1e-9);
  EXPECT_EQ(sampled->samples_in_body, 41 * 41 * 41);
}

TEST(LargestEmptySphere, GrowsWhenABlockOfVerticesIsRemoved) {
  const Volume volume = Uniform(100.0f);
  const double full = LargestEmptySphere(VolumeLatticeMesh(volume), volume, PositiveAbove50())->radius_mm;
  // Remove the 2x2x2 block around the cell corner at lattice (1.5, 1.5, 1.5).
  const ProxyMesh holed = VolumeLatticeMesh(volume, [](int a, int b, int c) {
    return !(a >= 1 && a <= 2 && b >= 1 && b <= 2 && c >= 1 && c <= 2);
  });
  auto sphere = LargestEmptySphere(holed, volume, PositiveAbove50());
  ASSERT_TRUE(sphere.ok());
  // The nearest survivors of the hole's centre sit at (+-0.5, +-0.5, +-1.5) cells.
  EXPECT_NEAR(sphere->radius_mm, kCellMm * std::sqrt(0.25 + 0.25 + 2.25), 1e-9);
  EXPECT_GT(sphere->radius_mm, 1.5 * full);
  EXPECT_NEAR(glm::distance(sphere->centre_mm, glm::dvec3(2.0 * kCellMm)), 0.0, 1e-6);
}

TEST(LargestEmptySphere, OnlyCentresInsideTheBodyCount) {
  // The body is the slab x < 12 mm; a hole at x ~ 20 mm is outside it.
  const Volume volume = MakeVolume({41, 41, 41}, {1.0, 1.0, 1.0}, [](int64_t i, int64_t, int64_t) {
    return i < 12 ? 100.0f : -1000.0f;
  });
  const ProxyMesh holed = VolumeLatticeMesh(volume, [](int a, int b, int c) {
    return !(a >= 2 && a <= 3 && b >= 1 && b <= 2 && c >= 1 && c <= 2);
  });
  auto sphere = LargestEmptySphere(holed, volume, PositiveAbove50());
  ASSERT_TRUE(sphere.ok());
  EXPECT_GT(PositiveAbove50().Evaluate(SampleTrilinear(volume, sphere->centre_mm)), 0.0);
  EXPECT_LT(sphere->centre_mm.x, 12.0);
  EXPECT_LT(sphere->radius_mm, kCellMm * std::sqrt(2.75) - 1e-3);
}

TEST(LargestEmptySphere, BoundarySamplesCatchSpheresCentredOutsideTheCircumcentres) {
  // A body too thin to hold any circumcentre: only samples find a sphere.
  const Volume volume = MakeVolume({41, 41, 41}, {1.0, 1.0, 1.0}, [](int64_t, int64_t j, int64_t) {
    return j == 20 ? 100.0f : -1000.0f;
  });
  const ProxyMesh mesh = VolumeLatticeMesh(volume);
  auto circumcentres = LargestEmptySphere(mesh, volume, PositiveAbove50());
  ASSERT_TRUE(circumcentres.ok());
  auto sampled = LargestEmptySphere(mesh, volume, PositiveAbove50(), {2});
  ASSERT_TRUE(sampled.ok());
  EXPECT_TRUE(sampled->centre_is_sample);
  EXPECT_GT(sampled->radius_mm, circumcentres->radius_mm);
  EXPECT_NEAR(sampled->centre_mm.y, 20.0, 1e-12);
}

TEST(LargestEmptySphere, RejectsAMeshWithoutVertices) {
  const Volume volume = Uniform(100.0f);
  EXPECT_FALSE(LargestEmptySphere(ProxyMesh{}, volume, PositiveAbove50()).ok());
}

}  // namespace
}  // namespace vpm

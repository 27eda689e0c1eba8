// Section 6 "Reconstruction error" and the piecewise-linear volume.
#include "server/common/clock.h"
#include "server/measures/reconstruction_error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "server/measures/interpolate_on_mesh.h"
#include "server/mesh/tetrahedralize.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm {
namespace {

using testing::LatticeMesh;
using testing::MakeVolume;
using testing::RandomMesh;

// A field linear in the index (so in mm); dyadic coefficients keep every
// voxel value exact in float.
Volume LinearVolume() {
  return MakeVolume({32, 24, 20}, {0.7, 1.3, 2.1}, [](int64_t i, int64_t j, int64_t k) {
    return static_cast<float>(2.0 + 0.5 * i + 0.25 * j - 0.125 * k);
  });
}

// 100 inside a ball of radius 10 voxels, -1000 outside.
Volume SphereVolume(std::array<int64_t, 3> dims) {
  return MakeVolume(dims, {1.0, 1.0, 1.0}, [dims](int64_t i, int64_t j, int64_t k) {
    const glm::dvec3 d = glm::dvec3(i, j, k) - glm::dvec3(dims[0], dims[1], dims[2]) * 0.5;
    return glm::length(d) < 10.0 ? 100.0f : -1000.0f;
  });
}

ProxyMesh MeshOver(const Volume& volume, ProxyMesh mesh) {
  EXPECT_TRUE(Tetrahedralize(mesh, volume.geometry().extent_mm()).ok());
  return mesh;
}

// TF > 0 only above 50: the sphere's inside.
TransferFunction SphereTf() { return *TransferFunction::Create({{50.0, 0.0}, {60.0, 1.0}}); }

TEST(ReconstructionError, IsZeroForALinearVolumeOnAnyMesh) {
  const Volume volume = LinearVolume();
  const glm::dvec3 extent = volume.geometry().extent_mm();
  for (uint32_t seed : {1u, 2u, 3u}) {
    const ProxyMesh mesh = MeshOver(volume, RandomMesh(40 * seed, extent, seed));
    auto error = MeasureReconstructionError(volume, mesh, TransferFunction::CtSoftTissue());
    ASSERT_TRUE(error.ok()) << error.status();
    EXPECT_LT(error->rmse_all, 1e-6);
    EXPECT_LT(error->rmse_tf_positive, 1e-6);
    EXPECT_EQ(error->voxels_all, volume.geometry().voxel_count());
    EXPECT_EQ(error->voxels_outside_mesh, 0);
  }
  const ProxyMesh lattice = MeshOver(volume, LatticeMesh(4, extent));
  EXPECT_LT(MeasureReconstructionError(volume, lattice, SphereTf())->rmse_all, 1e-6);
}

TEST(ReconstructionError, CoversEveryVoxelWhenFacesPassThroughVoxelCentres) {
  // 41^3 voxels, G = 5: lattice planes at voxel indices 4, 12, ..., 36, so
  // many voxel centres lie exactly on shared faces, edges and vertices.
  for (double scale : {1e-6, 1.0, 1e6}) {
    SCOPED_TRACE(scale);
    const Volume volume =
        MakeVolume({41, 41, 41}, glm::dvec3(scale), [](int64_t i, int64_t j, int64_t k) {
          return static_cast<float>(1.0 + 0.5 * i - 0.25 * j + 0.125 * k);
        });
    const ProxyMesh mesh = MeshOver(volume, LatticeMesh(5, volume.geometry().extent_mm()));
    auto error = MeasureReconstructionError(volume, mesh, SphereTf());
    ASSERT_TRUE(error.ok());
    EXPECT_EQ(error->voxels_all, volume.geometry().voxel_count());
    EXPECT_EQ(error->voxels_outside_mesh, 0);
    EXPECT_LT(error->rmse_all, 1e-6);
  }
}

TEST(ReconstructionError, IsPositiveForASphereAndMatchesTheInterpolatedVolume) {
  const Volume volume = SphereVolume({40, 36, 32});
  const ProxyMesh mesh = MeshOver(volume, LatticeMesh(5, volume.geometry().extent_mm()));
  const TransferFunction tf = SphereTf();
  auto error = MeasureReconstructionError(volume, mesh, tf);
  ASSERT_TRUE(error.ok());
  EXPECT_GT(error->rmse_all, 1.0);

  // The same numbers from the interpolated volume, voxel by voxel.
  auto interpolated = InterpolateOnMesh(volume, mesh);
  ASSERT_TRUE(interpolated.ok());
  double all = 0.0, positive = 0.0;
  int64_t positive_count = 0;
  for (size_t n = 0; n < interpolated->size(); ++n) {
    ASSERT_FALSE(std::isnan((*interpolated)[n])) << n;
    const double e = volume.voxels().floats()[n] - static_cast<double>((*interpolated)[n]);
    all += e * e;
    if (tf.Evaluate(volume.voxels().floats()[n]) > 0.0) {
      positive += e * e;
      ++positive_count;
    }
  }
  EXPECT_EQ(error->voxels_tf_positive, positive_count);
  EXPECT_GT(positive_count, 3000);  // (4/3) pi 10^3 = 4189 voxels
  EXPECT_LT(positive_count, 5000);
  EXPECT_NEAR(error->rmse_all, std::sqrt(all / volume.geometry().voxel_count()),
              1e-4 * error->rmse_all);
  EXPECT_NEAR(error->rmse_tf_positive, std::sqrt(positive / positive_count),
              1e-4 * error->rmse_tf_positive);
  EXPECT_NE(error->rmse_all, error->rmse_tf_positive);
}

TEST(ReconstructionError, InterpolationIsExactAtTheVertices) {
  const Volume volume = SphereVolume({21, 21, 21});
  // Vertices at voxel centres: the interpolant equals the volume there.
  ProxyMesh mesh;
  testing::AddAnchors(mesh, volume.geometry().extent_mm());
  for (int n = 0; n < 6; ++n) {
    MeshVertex v;
    v.position_mm = glm::dvec3(3 + 2 * n, 10 + (n % 3), 4 + 3 * n);
    mesh.vertices.push_back(v);
  }
  mesh = MeshOver(volume, mesh);
  auto interpolated = InterpolateOnMesh(volume, mesh);
  ASSERT_TRUE(interpolated.ok());
  for (const MeshVertex& v : mesh.vertices) {
    const glm::ivec3 i(v.position_mm);
    const int64_t n = volume.LinearIndex(i.x, i.y, i.z);
    EXPECT_FLOAT_EQ((*interpolated)[n], volume.voxels().floats()[n]);
  }
}

TEST(ReconstructionError, IsTheSameForAnyThreadCount) {
  const Volume volume = SphereVolume({30, 30, 30});
  const ProxyMesh mesh = MeshOver(volume, RandomMesh(120, volume.geometry().extent_mm(), 4));
  std::vector<ReconstructionError> results;
  for (int threads : {1, 2, 3, 7}) {
    auto error = MeasureReconstructionError(volume, mesh, SphereTf(), {threads});
    ASSERT_TRUE(error.ok());
    results.push_back(*error);
  }
  for (const ReconstructionError& r : results) {
    EXPECT_EQ(r.rmse_all, results[0].rmse_all);
    EXPECT_EQ(r.rmse_tf_positive, results[0].rmse_tf_positive);
    EXPECT_EQ(r.voxels_tf_positive, results[0].voxels_tf_positive);
  }
}

TEST(ReconstructionError, CountsVoxelsOutsideTheMesh) {
  const Volume volume = SphereVolume({20, 20, 20});  // box 19 mm
  // A mesh over the lower half in z only.
  const glm::dvec3 half(19.0, 19.0, 9.5);
  ProxyMesh mesh = RandomMesh(30, half, 8);
  ASSERT_TRUE(Tetrahedralize(mesh, half).ok());
  auto error = MeasureReconstructionError(volume, mesh, SphereTf());
  ASSERT_TRUE(error.ok());
  EXPECT_EQ(error->voxels_all, 20 * 20 * 10);
  EXPECT_EQ(error->voxels_outside_mesh, 20 * 20 * 10);
}

// 256^3 voxels at typical vertex counts: every voxel inside the mesh, and
// one or two threads give the same error. Its time is not asserted (a
// test's time follows the machine's load; speed belongs in bench/).
TEST(ReconstructionError, On256CubedVoxelsThreadsAgree) {
  const Volume volume = SphereVolume({256, 256, 256});
  const glm::dvec3 extent = volume.geometry().extent_mm();
  for (int g : {6, 10, 20}) {
    const ProxyMesh mesh = MeshOver(volume, LatticeMesh(g, extent));
    double rmse[2] = {0, 0};
    for (int threads : {1, 2}) {
      auto error = MeasureReconstructionError(volume, mesh, SphereTf(), {threads});
      ASSERT_TRUE(error.ok());
      std::printf("ReconstructionError 256^3, %5zu vertices %6zu tets, %d thread(s): rmse %.3f, "
                  "tf>0 %.3f\n",
                  mesh.vertices.size(), mesh.tets.size(), threads, error->rmse_all,
                  error->rmse_tf_positive);
      EXPECT_EQ(error->voxels_outside_mesh, 0);
      rmse[threads - 1] = error->rmse_all;
    }
    EXPECT_NEAR(rmse[0], rmse[1], 1e-9 * std::max(1.0, rmse[0]));
  }
}

}  // namespace
}  // namespace vpm

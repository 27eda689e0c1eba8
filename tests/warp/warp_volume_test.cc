// The warped volume J(x) = I(X(x)) (docs/ALGORITHM.md section 7) on the GPU,
// against its definition and the CPU references, for both ways of reading
// the source (sampler, texel buffer).
#include "server/warp/warp_volume.h"

#include <cmath>

#include <gtest/gtest.h>

#include "server/warp/backward_map_cpu.h"
#include "server/warp/warp_volume_cpu.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/mesh/mesh_test_volumes.h"
#include "tests/volume/int16_twin.h"
#include "tests/warp/warp_test_util.h"

namespace vpm {
namespace {

using testing::GpuTest;
using testing::LatticeWarpMesh;
using testing::MakeBodyVolume;
using testing::RandomlyMoved;
using testing::RandomWarpMesh;
using testing::WarpMesh;
using SourceRead = VolumeWarper::SourceRead;

constexpr SourceRead kReads[] = {SourceRead::kSampler, SourceRead::kTexelBuffer};

const char* Name(SourceRead read) { return read == SourceRead::kSampler ? "sampler" : "texel"; }

// Warps `source` on the GPU through a map of `map_dims` for the mesh.
Volume GpuWarp(gpu::GpuContext& context, const Volume& source, const WarpMesh& mesh,
               const std::vector<glm::dvec3>& deformed, std::array<int64_t, 3> map_dims,
               SourceRead read, BackwardMapValues* map_values = nullptr) {
  auto map = BackwardMap::Create(context, source.geometry(), {.map_dims = map_dims});
  auto gpu_volume = GpuVolume::Upload(context, source);
  auto warper = VolumeWarper::Create(context, {.source_read = read});
  if (!map.ok() || !gpu_volume.ok() || !warper.ok()) std::abort();
  if (!map->Update(mesh.rest_mm, deformed, mesh.tets).ok()) std::abort();
  if (map_values != nullptr) *map_values = *map->Download();
  auto warped = warper->Warp(*gpu_volume, source, *map);
  if (!warped.ok()) {
    ADD_FAILURE() << warped.status();
    std::abort();
  }
  return std::move(*warped);
}

// Tolerances below are measured on lavapipe, which filters in float, times
// about 5. Hardware samplers quantize the trilinear weights to
// subTexelPrecisionBits (8 on NVIDIA and AMD), which moves a sample by up to
// 2^-bits of a texel per axis, map and source each: across a 1100 HU edge
// that is up to 3 * 1100 * 2^-bits HU per lookup, allowed for on such devices.
double FilterTolerance(const gpu::GpuContext& context, double lavapipe_hu) {
  if (context.is_cpu_device()) return lavapipe_hu;
  return lavapipe_hu +
         2.0 * 3.0 * 1100.0 * std::ldexp(1.0, -int(context.limits().subTexelPrecisionBits));
}

double MaxAbsDiff(const Volume& a, const Volume& b) {
  double worst = 0.0;
  for (int64_t n = 0; n < a.voxels().size(); ++n) {
    worst = std::max(worst, double(std::abs(a.voxels()[n] - b.voxels()[n])));
  }
  return worst;
}

// deformed = rest: the exact map gives back every voxel bit for bit through
// the texel buffer (integer indices, weights exactly 0 and 1), and so does
// a coarse map (its displacement is exactly 0 too).
TEST_F(GpuTest, VolumeWarper_IdentityGivesBackTheVolume) {
  const Volume source = MakeBodyVolume({37, 29, 23}, {0.8, 1.1, 2.5});
  const WarpMesh mesh = RandomWarpMesh(40, source.geometry().extent_mm(), 9);
  for (SourceRead read : kReads) {
    for (std::array<int64_t, 3> dims : {source.dims(), std::array<int64_t, 3>{0, 0, 0}}) {
      SCOPED_TRACE(::testing::Message() << Name(read) << " map " << dims[0]);
      const Volume warped = GpuWarp(context(), source, mesh, mesh.rest_mm, dims, read);
      if (read == SourceRead::kTexelBuffer) {
        EXPECT_EQ(MaxAbsDiff(warped, source), 0.0);
      } else {
        // The sampler's texel coordinate (i + 0.5) / n * n - 0.5 is i only up
        // to float round-off (measured 0.003 HU at 1000 HU edges).
        EXPECT_LE(MaxAbsDiff(warped, source), FilterTolerance(context(), 0.01));
      }
    }
  }
}

// deformed = A rest + b with the box corners: J(x) = I(A^-1 (x - b)) for a
// volume linear in position, wherever the map cell around x lies inside the
// sheared box and its preimage inside the rest box.
TEST_F(GpuTest, VolumeWarper_AffineDeformationMatchesAnalyticAndCpu) {
  const std::array<int64_t, 3> dims{24, 20, 16};
  const glm::dvec3 spacing(1.0, 1.2, 1.5);
  const glm::dvec3 grad(2.0, -1.5, 3.0);  // HU/mm
  const Volume source = testing::LinearVolume(dims, spacing, 100.0, grad);
  const glm::dvec3 extent = source.geometry().extent_mm();
  const glm::dmat3 A(glm::dvec3(1.04, 0.02, -0.03), glm::dvec3(0.05, 0.97, 0.01),
                     glm::dvec3(-0.01, 0.04, 1.02));
  const glm::dvec3 b = glm::dvec3(0.01, -0.02, 0.015) * extent;
  const glm::dmat3 A_inv = glm::inverse(A);
  const WarpMesh mesh = LatticeWarpMesh(3, extent);
  std::vector<glm::dvec3> deformed;
  for (const glm::dvec3& r : mesh.rest_mm) deformed.push_back(A * r + b);
  for (SourceRead read : kReads) {
    for (std::array<int64_t, 3> map_dims : {dims, std::array<int64_t, 3>{0, 0, 0}}) {
      SCOPED_TRACE(::testing::Message() << Name(read) << " map " << map_dims[0]);
      BackwardMapValues map;
      const Volume warped = GpuWarp(context(), source, mesh, deformed, map_dims, read, &map);
      auto cpu_map = BackwardMapCpu(extent, map.dims, mesh.rest_mm, deformed, mesh.tets);
      ASSERT_TRUE(cpu_map.ok());
      auto cpu = WarpVolumeCpu(source, *cpu_map);
      ASSERT_TRUE(cpu.ok()) << cpu.status();
      // Measured <= 5e-5 HU (values up to 200 HU, float).
      EXPECT_LE(MaxAbsDiff(warped, *cpu), FilterTolerance(context(), 1e-3));
      int64_t checked = 0;
      double max_err = 0.0;
      for (int64_t k = 0; k < dims[2]; ++k) {
        for (int64_t j = 0; j < dims[1]; ++j) {
          for (int64_t i = 0; i < dims[0]; ++i) {
            const glm::dvec3 x = source.geometry().IndexToPhysical(glm::dvec3(i, j, k));
            const glm::dvec3 rest = A_inv * (x - b);
            // Map corners around x all inside: a tiny box around x maps to
            // points inside the mesh when the step-size box does.
            const glm::dvec3 h = map.StepMm();
            bool inside = glm::all(glm::greaterThanEqual(rest, glm::dvec3(0.0))) &&
                          glm::all(glm::lessThanEqual(rest, extent));
            for (int c = 0; c < 8 && inside; ++c) {
              const glm::dvec3 corner =
                  glm::floor(x / h) * h + glm::dvec3(c & 1, (c >> 1) & 1, (c >> 2) & 1) * h;
              inside = map.Sample(glm::min(corner, extent)).w == 1.0;
            }
            if (!inside) continue;
            ++checked;
            const double expected = 100.0 + glm::dot(grad, rest);
            max_err = std::max(max_err, std::abs(warped.At(i, j, k) - expected));
          }
        }
      }
      EXPECT_GT(checked, dims[0] * dims[1] * dims[2] / 5);
      EXPECT_LE(max_err, FilterTolerance(context(), 1e-3));  // measured <= 4e-5 HU
    }
  }
}

// A random deformation of a Delaunay mesh over a volume with sharp edges
// (1000 HU steps within a voxel): the GPU warp against the CPU arithmetic
// through the same (downloaded) map, and the exact GPU warp against the
// exact CPU warp.
TEST_F(GpuTest, VolumeWarper_MatchesCpuReferenceOnRandomDeformation) {
  const Volume source = MakeBodyVolume({37, 29, 23}, {0.8, 1.1, 2.5});
  const glm::dvec3 extent = source.geometry().extent_mm();
  const WarpMesh mesh = RandomWarpMesh(60, extent, 21);
  const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 1.5, 22);
  auto exact_cpu = WarpVolumeExactCpu(source, mesh.rest_mm, deformed, mesh.tets);
  ASSERT_TRUE(exact_cpu.ok()) << exact_cpu.status();
  EXPECT_GT(MaxAbsDiff(*exact_cpu, source), 100.0);  // it did move
  for (SourceRead read : kReads) {
    SCOPED_TRACE(Name(read));
    BackwardMapValues map;
    const Volume coarse = GpuWarp(context(), source, mesh, deformed, {0, 0, 0}, read, &map);
    auto coarse_cpu = WarpVolumeCpu(source, map);
    ASSERT_TRUE(coarse_cpu.ok());
    // Measured <= 0.004 HU: float positions (~1e-5 mm) across 1250 HU/mm edges.
    EXPECT_LE(MaxAbsDiff(coarse, *coarse_cpu), FilterTolerance(context(), 0.02));
    const Volume exact = GpuWarp(context(), source, mesh, deformed, source.dims(), read);
    EXPECT_LE(MaxAbsDiff(exact, *exact_cpu), FilterTolerance(context(), 0.02));
  }
}

// The body volume rounded to integer HU, as int16 and as float: the texel
// warp of both is the same, bit for bit, and matches the CPU arithmetic; the
// sampler reads the int16 volume's R16_UNORM image within 65535 * 2^-24 HU
// per voxel of the float one (plus the filter's tolerance).
TEST_F(GpuTest, VolumeWarper_Int16SourceWarpsLikeFloat) {
  const Volume body = MakeBodyVolume({37, 29, 23}, {0.8, 1.1, 2.5});
  const auto [int16, floats] = testing::MakeInt16Twin(body);
  const WarpMesh mesh = RandomWarpMesh(60, body.geometry().extent_mm(), 21);
  const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 1.5, 22);
  for (SourceRead read : kReads) {
    SCOPED_TRACE(Name(read));
    BackwardMapValues map;
    const Volume a = GpuWarp(context(), int16, mesh, deformed, {0, 0, 0}, read, &map);
    const Volume b = GpuWarp(context(), floats, mesh, deformed, {0, 0, 0}, read);
    EXPECT_GT(MaxAbsDiff(a, int16), 100.0);  // it did move
    if (read == SourceRead::kTexelBuffer) {
      EXPECT_EQ(MaxAbsDiff(a, b), 0.0);
    } else {
      EXPECT_LE(MaxAbsDiff(a, b), FilterTolerance(context(), 0.01));
    }
    auto cpu = WarpVolumeCpu(int16, map);
    ASSERT_TRUE(cpu.ok()) << cpu.status();
    EXPECT_LE(MaxAbsDiff(a, *cpu), FilterTolerance(context(), 0.02));
  }
}

TEST(WarpVolumeCpu, ExactWarpEqualsWarpThroughAFullResolutionMap) {
  const Volume source = MakeBodyVolume({20, 18, 14}, {1.0, 1.2, 1.5});
  const glm::dvec3 extent = source.geometry().extent_mm();
  const WarpMesh mesh = RandomWarpMesh(30, extent, 5);
  const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 1.0, 6);
  auto map = BackwardMapCpu(extent, source.dims(), mesh.rest_mm, deformed, mesh.tets);
  ASSERT_TRUE(map.ok());
  auto through_map = WarpVolumeCpu(source, *map, 1);
  auto exact = WarpVolumeExactCpu(source, mesh.rest_mm, deformed, mesh.tets, {.threads = 3});
  ASSERT_TRUE(through_map.ok() && exact.ok());
  // The map stores the displacement in float: ~1e-6 mm, times 1000 HU/voxel
  // (measured 6e-5 HU).
  EXPECT_LE(MaxAbsDiff(*through_map, *exact), 1e-3);
  EXPECT_EQ(exact->geometry().dims, source.dims());
}

TEST_F(GpuTest, VolumeWarper_KeepsTheSourceGeometryForExport) {
  Volume source = MakeBodyVolume({16, 14, 12}, {1.0, 1.2, 1.5});
  VolumeGeometry g = source.geometry();
  g.origin_mm = {-12.5, 40.0, 7.25};
  g.direction = glm::dmat3(glm::dvec3(0, 1, 0), glm::dvec3(-1, 0, 0), glm::dvec3(0, 0, 1));
  source = *Volume::Create(g, std::vector<float>(source.voxels().floats().begin(), source.voxels().floats().end()));
  source.set_source("phantom:test");
  const WarpMesh mesh = RandomWarpMesh(10, g.extent_mm(), 2);
  const Volume warped = GpuWarp(context(), source, mesh, RandomlyMoved(mesh, 1.0, 3), {0, 0, 0},
                                SourceRead::kSampler);
  EXPECT_EQ(warped.geometry().dims, g.dims);
  EXPECT_EQ(warped.geometry().spacing_mm, g.spacing_mm);
  EXPECT_EQ(warped.geometry().origin_mm, g.origin_mm);
  EXPECT_EQ(warped.geometry().direction, g.direction);
  EXPECT_EQ(warped.source(), "phantom:test (warped)");
}

TEST_F(GpuTest, VolumeWarper_RejectsAMapOfAnotherVolumeAndShortOutput) {
  const Volume source = MakeBodyVolume({16, 14, 12}, {1.0, 1.2, 1.5});
  const Volume other = MakeBodyVolume({16, 14, 12}, {1.0, 1.0, 1.0});
  auto gpu_volume = GpuVolume::Upload(context(), source);
  auto map = BackwardMap::Create(context(), other.geometry());
  auto warper = VolumeWarper::Create(context());  // the texel buffer by default
  ASSERT_TRUE(gpu_volume.ok() && map.ok() && warper.ok());
  EXPECT_EQ(warper->Warp(*gpu_volume, source, *map).status().code(),
            absl::StatusCode::kInvalidArgument);
  auto own_map = BackwardMap::Create(context(), source.geometry());
  auto small = gpu::GpuBuffer::Create(context(), 64, vk::BufferUsageFlagBits::eStorageBuffer);
  auto batch = gpu::ComputeBatch::Begin(context(), 1);
  ASSERT_TRUE(own_map.ok() && small.ok() && batch.ok());
  EXPECT_EQ(warper->Record(*batch, *gpu_volume, nullptr, *own_map, *small).code(),
            absl::StatusCode::kInvalidArgument);
  auto sampler = VolumeWarper::Create(context(), {.source_read = SourceRead::kSampler});
  auto big = gpu::GpuBuffer::Create(context(), source.voxels().floats().size() * 4,
                                    vk::BufferUsageFlagBits::eStorageBuffer);
  ASSERT_TRUE(sampler.ok() && big.ok());
  EXPECT_EQ(sampler->Record(*batch, *gpu_volume, nullptr, *own_map, *big).code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace vpm

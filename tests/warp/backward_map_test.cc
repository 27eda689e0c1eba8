// The backward map (docs/ALGORITHM.md section 7, docs/WARP.md) on the GPU against
// its definition and its CPU reference.
#include "server/warp/backward_map.h"

#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "server/warp/backward_map_cpu.h"
#include "tests/gpu/gpu_test_context.h"
#include "tests/warp/warp_test_util.h"

namespace vpm {
namespace {

using testing::Dragged;
using testing::GpuTest;
using testing::LatticeWarpMesh;
using testing::RandomlyMoved;
using testing::RandomWarpMesh;
using testing::WarpMesh;

VolumeGeometry Geometry(std::array<int64_t, 3> dims, glm::dvec3 spacing_mm) {
  VolumeGeometry g;
  g.dims = dims;
  g.spacing_mm = spacing_mm;
  return g;
}

// Incremental whatever moved, so that the tests exercise the clear pass.
BackwardMap MakeMap(gpu::GpuContext& context, const VolumeGeometry& g,
                    std::array<int64_t, 3> map_dims, double full_rebuild_moved_fraction = 1.0) {
  auto map = BackwardMap::Create(
      context, g, {.map_dims = map_dims, .full_rebuild_moved_fraction = full_rebuild_moved_fraction});
  if (!map.ok()) {
    ADD_FAILURE() << map.status();
    std::abort();
  }
  return std::move(*map);
}

BackwardMapValues Download(const BackwardMap& map) {
  auto values = map.Download();
  EXPECT_TRUE(values.ok()) << values.status();
  return values.ok() ? std::move(*values) : BackwardMapValues{};
}

bool BitwiseEqual(const BackwardMapValues& a, const BackwardMapValues& b) {
  return a.values.size() == b.values.size() &&
         std::memcmp(a.values.data(), b.values.data(), a.values.size() * sizeof(glm::vec4)) == 0;
}

TEST(BackwardMapDims, DefaultIsAQuarterRoundedUpAndAtLeastTwo) {
  EXPECT_EQ(DefaultBackwardMapDims({256, 256, 256}), (std::array<int64_t, 3>{64, 64, 64}));
  EXPECT_EQ(DefaultBackwardMapDims({37, 29, 5}), (std::array<int64_t, 3>{10, 8, 2}));
  EXPECT_EQ(DefaultBackwardMapDims({2, 3, 9}), (std::array<int64_t, 3>{2, 2, 3}));
  // A full-size CT: the map follows the mesh, not the slice count.
  EXPECT_EQ(DefaultBackwardMapDims({512, 512, 900}), (std::array<int64_t, 3>{64, 64, 64}));
}

TEST_F(GpuTest, BackwardMap_NewMapAndIdentityDeformationAreZero) {
  const VolumeGeometry g = Geometry({21, 17, 13}, {0.7, 1.1, 2.0});
  BackwardMap map = MakeMap(context(), g, {0, 0, 0});
  EXPECT_EQ(map.dims(), (std::array<int64_t, 3>{6, 5, 4}));
  for (const glm::vec4& v : Download(map).values) EXPECT_EQ(v, glm::vec4(0.0f));

  const WarpMesh mesh = RandomWarpMesh(30, g.extent_mm(), 3);
  auto stats = map.Update(mesh.rest_mm, mesh.rest_mm, mesh.tets);
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_TRUE(stats->full_rebuild);
  // The mesh covers the box: every point inside, displacement exactly 0.
  for (const glm::vec4& v : Download(map).values) EXPECT_EQ(v, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
}

// deformed = A rest + b on every vertex, box corners included, so the box
// maps onto a sheared box: inside it the map is the affine inverse, outside
// it every point is outside the mesh (inside 0, displacement 0).
void ExpectAffineInverse(gpu::GpuContext& context, const VolumeGeometry& g,
                         std::array<int64_t, 3> map_dims, double tolerance_mm) {
  const glm::dmat3 A(glm::dvec3(1.06, 0.03, -0.04), glm::dvec3(0.07, 0.95, 0.02),
                     glm::dvec3(-0.02, 0.05, 1.03));  // columns
  const glm::dvec3 b = glm::dvec3(0.021, -0.013, 0.017) * g.extent_mm();
  const glm::dmat3 A_inv = glm::inverse(A);
  const WarpMesh mesh = LatticeWarpMesh(3, g.extent_mm());
  std::vector<glm::dvec3> deformed;
  for (const glm::dvec3& r : mesh.rest_mm) deformed.push_back(A * r + b);
  BackwardMap map = MakeMap(context, g, map_dims);
  ASSERT_TRUE(map.Update(mesh.rest_mm, deformed, mesh.tets).ok());
  const BackwardMapValues values = Download(map);
  const glm::dvec3 extent = g.extent_mm();
  int64_t inside = 0, outside = 0;
  for (int64_t c = 0; c < map.dims()[2]; ++c) {
    for (int64_t bb = 0; bb < map.dims()[1]; ++bb) {
      for (int64_t a = 0; a < map.dims()[0]; ++a) {
        const glm::dvec3 p = values.GridPointMm(a, bb, c);
        const glm::dvec3 rest = A_inv * (p - b);
        // How far inside the rest box the preimage lies (negative: outside).
        const glm::dvec3 margin = glm::min(rest, extent - rest) / extent;
        const double depth = std::min({margin.x, margin.y, margin.z});
        const glm::vec4 v = values.At(a, bb, c);
        if (v.w == 1.0f) {
          ++inside;
          EXPECT_GT(depth, -1e-4) << "point " << a << "," << bb << "," << c;
          const glm::dvec3 d = rest - p;
          EXPECT_LE(glm::length(glm::dvec3(v) - d), tolerance_mm)
              << "point " << a << "," << bb << "," << c;
        } else {
          ++outside;
          EXPECT_EQ(v, glm::vec4(0.0f)) << "point " << a << "," << bb << "," << c;
          EXPECT_LT(depth, 1e-4) << "point " << a << "," << bb << "," << c;
        }
      }
    }
  }
  EXPECT_GT(inside, 0);
  EXPECT_GT(outside, 0);
}

TEST_F(GpuTest, BackwardMap_AffineDeformationGivesTheAffineInverse) {
  const VolumeGeometry g = Geometry({24, 20, 16}, {1.0, 1.2, 1.5});
  ExpectAffineInverse(context(), g, {0, 0, 0}, 1e-4);
  ExpectAffineInverse(context(), g, {11, 7, 9}, 1e-4);
  ExpectAffineInverse(context(), g, g.dims, 1e-4);
}

// The same at voxel sizes of 1 um and 1 m: the error scales with the volume.
TEST_F(GpuTest, BackwardMap_AffineInverseAtExtremeScales) {
  for (double scale : {1e-3, 1e3}) {
    SCOPED_TRACE(scale);
    ExpectAffineInverse(context(), Geometry({16, 14, 12}, glm::dvec3(1.0, 1.2, 1.5) * scale),
                        {0, 0, 0}, 1e-4 * scale);
  }
}

// Random small deformations of Delaunay meshes, anisotropic spacing, map
// dims that are not multiples of anything.
TEST_F(GpuTest, BackwardMap_MatchesCpuReferenceOnRandomDeformation) {
  const VolumeGeometry g = Geometry({37, 29, 23}, {0.8, 1.1, 2.5});
  for (uint32_t seed : {1u, 2u}) {
    SCOPED_TRACE(seed);
    const WarpMesh mesh = RandomWarpMesh(60, g.extent_mm(), seed);
    const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 1.5, seed + 10);
    for (std::array<int64_t, 3> dims : {std::array<int64_t, 3>{0, 0, 0}, {13, 31, 7}, g.dims}) {
      BackwardMap map = MakeMap(context(), g, dims);
      ASSERT_TRUE(map.Update(mesh.rest_mm, deformed, mesh.tets).ok());
      const BackwardMapValues gpu = Download(map);
      auto cpu = BackwardMapCpu(g.extent_mm(), map.dims(), mesh.rest_mm, deformed, mesh.tets);
      ASSERT_TRUE(cpu.ok()) << cpu.status();
      ASSERT_EQ(gpu.values.size(), cpu->values.size());
      double max_err = 0.0, max_d = 0.0;
      int64_t flag_mismatch = 0;
      for (size_t n = 0; n < gpu.values.size(); ++n) {
        flag_mismatch += gpu.values[n].w != cpu->values[n].w;
        max_err = std::max(max_err, double(glm::length(gpu.values[n] - cpu->values[n])));
        max_d = std::max(max_d, double(glm::length(glm::vec3(cpu->values[n]))));
      }
      EXPECT_EQ(flag_mismatch, 0);
      EXPECT_LE(max_err, 1e-4) << "max displacement " << max_d << " mm";
      EXPECT_GT(max_d, 0.5);
    }
  }
}

// Local drags, a second drag elsewhere, and the release: each incremental
// update gives the full rebuild's map bit for bit, on a coarse and on the
// exact grid.
TEST_F(GpuTest, BackwardMap_MovedTetsUpdateEqualsFullRebuild) {
  const VolumeGeometry g = Geometry({40, 36, 30}, {1.0, 1.1, 1.3});
  const glm::dvec3 e = g.extent_mm();
  const WarpMesh mesh = RandomWarpMesh(150, e, 7);
  const std::vector<std::vector<glm::dvec3>> steps = {
      mesh.rest_mm, Dragged(mesh, e * 0.3, 0.25 * e.x, {2.0, -1.0, 1.5}),
      Dragged(mesh, e * 0.3, 0.25 * e.x, {3.0, -1.5, 2.0}),
      Dragged(mesh, e * 0.7, 0.2 * e.x, {-2.0, 1.0, 0.5}), mesh.rest_mm};
  for (std::array<int64_t, 3> dims : {std::array<int64_t, 3>{0, 0, 0}, g.dims}) {
    BackwardMap incremental = MakeMap(context(), g, dims);
    BackwardMap listed = MakeMap(context(), g, dims);
    std::vector<glm::dvec3> previous;
    for (size_t s = 0; s < steps.size(); ++s) {
      SCOPED_TRACE(::testing::Message() << "step " << s << " map " << dims[0]);
      auto stats = incremental.Update(mesh.rest_mm, steps[s], mesh.tets);
      ASSERT_TRUE(stats.ok()) << stats.status();
      EXPECT_EQ(stats->full_rebuild, s == 0);
      if (s > 0) {
        EXPECT_GT(stats->moved_tets, 0);
        EXPECT_LT(stats->processed_tets, static_cast<int64_t>(mesh.tets.size()));
      }
      // The caller's list: every tet with a vertex that moved since last time.
      std::vector<int32_t> moved;
      for (size_t t = 0; t < mesh.tets.size(); ++t) {
        for (int32_t v : mesh.tets[t]) {
          if (s > 0 && steps[s][v] != previous[v]) {
            moved.push_back(static_cast<int32_t>(t));
            break;
          }
        }
      }
      ASSERT_TRUE(listed.UpdateListed(mesh.rest_mm, steps[s], mesh.tets, moved).ok());
      previous = steps[s];
      BackwardMap full = MakeMap(context(), g, dims);
      ASSERT_TRUE(full.Rebuild(mesh.rest_mm, steps[s], mesh.tets).ok());
      const BackwardMapValues expected = Download(full);
      EXPECT_TRUE(BitwiseEqual(Download(incremental), expected));
      EXPECT_TRUE(BitwiseEqual(Download(listed), expected));
    }
  }
}

// By default an update that moves most tets (every free vertex moves under
// FEM) rebuilds instead of clearing them one by one; a local drag stays
// incremental; both give the incremental map bit for bit.
TEST_F(GpuTest, BackwardMap_UpdateMovingMostTetsRebuildsTheSameMap) {
  const VolumeGeometry g = Geometry({40, 36, 30}, {1.0, 1.1, 1.3});
  const glm::dvec3 e = g.extent_mm();
  const WarpMesh mesh = RandomWarpMesh(150, e, 7);
  BackwardMap by_default = MakeMap(context(), g, {0, 0, 0}, 0.5);
  BackwardMap incremental = MakeMap(context(), g, {0, 0, 0});
  for (auto* map : {&by_default, &incremental}) {
    ASSERT_TRUE(map->Update(mesh.rest_mm, mesh.rest_mm, mesh.tets).ok());
  }
  const std::vector<std::vector<glm::dvec3>> steps = {
      Dragged(mesh, e * 0.3, 0.25 * e.x, {2.0, -1.0, 1.5}), RandomlyMoved(mesh, 1.0, 5),
      RandomlyMoved(mesh, 1.5, 6)};
  for (size_t s = 0; s < steps.size(); ++s) {
    SCOPED_TRACE(::testing::Message() << "step " << s);
    auto stats = by_default.Update(mesh.rest_mm, steps[s], mesh.tets);
    ASSERT_TRUE(stats.ok()) << stats.status();
    auto incremental_stats = incremental.Update(mesh.rest_mm, steps[s], mesh.tets);
    ASSERT_TRUE(incremental_stats.ok()) << incremental_stats.status();
    EXPECT_FALSE(incremental_stats->full_rebuild);
    EXPECT_EQ(stats->full_rebuild, 2 * stats->moved_tets > int64_t(mesh.tets.size()));
    EXPECT_EQ(stats->full_rebuild, s > 0);
    EXPECT_TRUE(BitwiseEqual(Download(by_default), Download(incremental)));
  }
}

// With a move tolerance (the interactive map, DeformableScene), vertices
// that moved less than it since the map last took them keep their old
// positions: the map equals, bit for bit, the rebuild of the mesh at the
// positions it holds (tracked here independently), the far vertices' small
// moves do not list their tets, and a vertex that drifts past the tolerance
// over several steps is taken up.
TEST_F(GpuTest, BackwardMap_MoveToleranceHoldsSmallMovesOnly) {
  const VolumeGeometry g = Geometry({40, 36, 30}, {1.0, 1.1, 1.3});
  const glm::dvec3 e = g.extent_mm();
  const WarpMesh mesh = RandomWarpMesh(150, e, 7);
  const double tolerance = 0.05;
  auto created = BackwardMap::Create(
      context(), g, {.full_rebuild_moved_fraction = 1.0, .move_tolerance_mm = tolerance});
  ASSERT_TRUE(created.ok()) << created.status();
  BackwardMap map = std::move(*created);
  ASSERT_TRUE(map.Update(mesh.rest_mm, mesh.rest_mm, mesh.tets).ok());
  std::vector<glm::dvec3> held = mesh.rest_mm;  // what the map should hold
  for (int s = 1; s <= 4; ++s) {
    SCOPED_TRACE(::testing::Message() << "step " << s);
    // A drag around one point, and everywhere a drift of 0.02 mm per step
    // per axis (past the tolerance at the third step).
    const auto dragged = Dragged(mesh, e * 0.3, 0.25 * e.x, {0.8 * s, -0.4 * s, 0.6 * s});
    std::vector<glm::dvec3> step = dragged;
    for (size_t v = 0; v < step.size(); ++v) {
      if (!mesh.anchor[v]) step[v] += glm::dvec3(0.02 * s, -0.02 * s, 0.01 * s);
    }
    int64_t expect_held = 0;
    for (size_t v = 0; v < step.size(); ++v) {
      const glm::dvec3 d = glm::abs(step[v] - held[v]);
      if (step[v] == held[v]) continue;
      if (std::max(d.x, std::max(d.y, d.z)) <= tolerance) {
        ++expect_held;
      } else {
        held[v] = step[v];
      }
    }
    auto stats = map.Update(mesh.rest_mm, step, mesh.tets);
    ASSERT_TRUE(stats.ok()) << stats.status();
    EXPECT_FALSE(stats->full_rebuild);
    EXPECT_EQ(stats->held_vertices, expect_held);
    if (s % 3 != 0) {
      EXPECT_GT(stats->held_vertices, 0);
      EXPECT_LT(stats->processed_tets, static_cast<int64_t>(mesh.tets.size()));
    }
    BackwardMap full = MakeMap(context(), g, {0, 0, 0});
    ASSERT_TRUE(full.Rebuild(mesh.rest_mm, held, mesh.tets).ok());
    EXPECT_TRUE(BitwiseEqual(Download(map), Download(full)));
  }
}

// Values split over 3 slabs of whole z slices (as maps over 8M points are
// on lavapipe) give the single-buffer map bit for bit, also incrementally;
// too many slabs are refused.
TEST_F(GpuTest, BackwardMap_ValueSlabsGiveTheSameMap) {
  const VolumeGeometry g = Geometry({30, 26, 22}, {1.0, 1.1, 1.3});
  const WarpMesh mesh = RandomWarpMesh(60, g.extent_mm(), 12);
  const glm::dvec3 e = g.extent_mm();
  const std::array<int64_t, 3> dims{17, 13, 11};
  auto one = BackwardMap::Create(context(), g, {.map_dims = dims});
  auto three =
      BackwardMap::Create(context(), g, {.map_dims = dims, .max_slab_bytes = 4 * 17 * 13 * 16});
  ASSERT_TRUE(one.ok() && three.ok());
  for (const auto& deformed :
       {RandomlyMoved(mesh, 1.0, 13), Dragged(mesh, e * 0.5, 8.0, {1, 2, 1})}) {
    ASSERT_TRUE(one->Update(mesh.rest_mm, deformed, mesh.tets).ok());
    ASSERT_TRUE(three->Update(mesh.rest_mm, deformed, mesh.tets).ok());
    EXPECT_TRUE(BitwiseEqual(Download(*one), Download(*three)));
    // The single-buffer map exposes its values buffer, equal to the image.
    ASSERT_NE(one->values_buffer(), nullptr);
    BackwardMapValues buffer = Download(*one);
    ASSERT_TRUE(one->values_buffer()->DownloadSpan(std::span<glm::vec4>(buffer.values)).ok());
    EXPECT_TRUE(BitwiseEqual(buffer, Download(*one)));
  }
  EXPECT_EQ(three->values_buffer(), nullptr);
  EXPECT_EQ(
      BackwardMap::Create(context(), g, {.map_dims = dims, .max_slab_bytes = 2 * 17 * 13 * 16})
          .status()
          .code(),
      absl::StatusCode::kResourceExhausted);
}

// A mesh over part of the box only: the points it does not cover are outside
// (inside 0) with displacement 0, the identity.
TEST_F(GpuTest, BackwardMap_PointsOutsideEveryTetAreIdentity) {
  const VolumeGeometry g = Geometry({20, 20, 20}, {1.0, 1.0, 1.0});
  // Two tets forming a wedge in the lower corner of the 19 mm box.
  const std::vector<glm::dvec3> rest = {
      {0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {0, 0, 10}, {10, 10, 10}};
  const std::vector<std::array<int32_t, 4>> tets = {{0, 1, 2, 3}, {1, 2, 3, 4}};
  std::vector<glm::dvec3> deformed = rest;
  for (glm::dvec3& p : deformed) p += glm::dvec3(0.5, 0.25, -0.5) * (p.x / 10.0);
  BackwardMap map = MakeMap(context(), g, {0, 0, 0});
  ASSERT_TRUE(map.Update(rest, deformed, tets).ok());
  const BackwardMapValues gpu = Download(map);
  auto cpu = BackwardMapCpu(g.extent_mm(), map.dims(), rest, deformed, tets);
  ASSERT_TRUE(cpu.ok());
  int64_t outside = 0, inside = 0;
  for (size_t n = 0; n < gpu.values.size(); ++n) {
    EXPECT_EQ(gpu.values[n].w, cpu->values[n].w) << n;
    if (gpu.values[n].w == 0.0f) {
      ++outside;
      EXPECT_EQ(gpu.values[n], glm::vec4(0.0f));
    } else {
      ++inside;
      EXPECT_LE(glm::length(gpu.values[n] - cpu->values[n]), 1e-4);
    }
  }
  EXPECT_GT(inside, 5);
  EXPECT_GT(outside, inside);
  // Moving the mesh away entirely clears its old coverage.
  for (glm::dvec3& p : deformed) p += glm::dvec3(100.0, 0.0, 0.0);
  auto stats = map.Update(rest, deformed, tets);
  ASSERT_TRUE(stats.ok());
  EXPECT_FALSE(stats->full_rebuild);
  for (const glm::vec4& v : Download(map).values) EXPECT_EQ(v, glm::vec4(0.0f));
}

TEST_F(GpuTest, BackwardMap_RejectsBadInputsAndKeepsItsContent) {
  const VolumeGeometry g = Geometry({16, 16, 16}, {1.0, 1.0, 1.0});
  const WarpMesh mesh = RandomWarpMesh(20, g.extent_mm(), 4);
  const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 1.0, 5);
  BackwardMap map = MakeMap(context(), g, {0, 0, 0});
  ASSERT_TRUE(map.Update(mesh.rest_mm, deformed, mesh.tets).ok());
  const BackwardMapValues before = Download(map);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto bad_index = mesh.tets;
  bad_index[3][2] = static_cast<int32_t>(mesh.rest_mm.size());
  auto negative_index = mesh.tets;
  negative_index[0][0] = -1;
  auto nan_deformed = deformed;
  nan_deformed[5].y = nan;
  auto nan_rest = mesh.rest_mm;
  nan_rest[2].z = std::numeric_limits<double>::infinity();
  auto short_deformed = deformed;
  short_deformed.pop_back();
  const std::vector<int32_t> bad_moved = {0, static_cast<int32_t>(mesh.tets.size())};

  std::vector<Status> errors = {
      map.Update(mesh.rest_mm, deformed, bad_index).status(),
      map.Update(mesh.rest_mm, deformed, negative_index).status(),
      map.Update(mesh.rest_mm, nan_deformed, mesh.tets).status(),
      map.Rebuild(nan_rest, deformed, mesh.tets).status(),
      map.Update(mesh.rest_mm, short_deformed, mesh.tets).status(),
      map.UpdateListed(mesh.rest_mm, deformed, mesh.tets, bad_moved).status()};
  for (const Status& s : errors) {
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  }
  EXPECT_TRUE(BitwiseEqual(Download(map), before));
  // The CPU reference rejects the same inputs.
  EXPECT_FALSE(BackwardMapCpu(g.extent_mm(), map.dims(), mesh.rest_mm, deformed, bad_index).ok());
  EXPECT_FALSE(
      BackwardMapCpu(g.extent_mm(), map.dims(), mesh.rest_mm, nan_deformed, mesh.tets).ok());
  EXPECT_FALSE(
      BackwardMapCpu(g.extent_mm(), map.dims(), mesh.rest_mm, short_deformed, mesh.tets).ok());
  // After the errors an update still works and is incremental.
  auto stats = map.Update(mesh.rest_mm, mesh.rest_mm, mesh.tets);
  ASSERT_TRUE(stats.ok()) << stats.status();
  EXPECT_FALSE(stats->full_rebuild);

  EXPECT_EQ(BackwardMap::Create(context(), g, {.map_dims = {1, 4, 4}}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(BackwardMap::Create(context(), g, {.map_dims = {4, 4, -2}}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(BackwardMap::Create(context(), Geometry({16, 1, 16}, {1, 1, 1})).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(BackwardMap::Create(context(), g, {.eps = -1.0}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// An empty mesh and a flat tet (zero volume) contain no point.
TEST_F(GpuTest, BackwardMap_EmptyMeshAndFlatTetsCoverNothing) {
  const VolumeGeometry g = Geometry({12, 12, 12}, {1.0, 1.0, 1.0});
  BackwardMap map = MakeMap(context(), g, {0, 0, 0});
  ASSERT_TRUE(map.Update({}, {}, {}).ok());
  for (const glm::vec4& v : Download(map).values) EXPECT_EQ(v, glm::vec4(0.0f));
  const std::vector<glm::dvec3> flat = {{0, 0, 0}, {11, 0, 0}, {0, 11, 0}, {5, 5, 0}};
  const std::vector<std::array<int32_t, 4>> flat_tet = {{0, 1, 2, 3}};
  ASSERT_TRUE(map.Update(flat, flat, flat_tet).ok());
  for (const glm::vec4& v : Download(map).values) EXPECT_EQ(v, glm::vec4(0.0f));
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

// Few, large tets on a fine grid: a lane of the claim pass walks thousands of
// rows of a thousand points. llvmpipe (Mesa 22.3) ends an invocation's loops
// silently after 65,535 iterations in all, which left the far rows of such
// tets without an owner; the work is now cut into slabs of z-slices.
TEST_F(GpuTest, BackwardMap_LargeTetsOnAFineGridAreClaimedWhole) {
  // The phantom's box (378.5 x 378.5 x 239.1 mm) on 256 x 256 x 160 points.
  const VolumeGeometry g = Geometry({256, 256, 160}, {378.5 / 255, 378.5 / 255, 239.1 / 159});
  const WarpMesh mesh = RandomWarpMesh(5, g.extent_mm(), 3);
  const std::vector<glm::dvec3> deformed = RandomlyMoved(mesh, 3.0, 11);
  BackwardMap map = MakeMap(context(), g, g.dims);
  ASSERT_TRUE(map.Update(mesh.rest_mm, deformed, mesh.tets).ok());
  const BackwardMapValues gpu = Download(map);
  auto cpu = BackwardMapCpu(g.extent_mm(), map.dims(), mesh.rest_mm, deformed, mesh.tets);
  ASSERT_TRUE(cpu.ok()) << cpu.status();
  int64_t flag_mismatch = 0;
  double max_err = 0.0;
  for (size_t n = 0; n < gpu.values.size(); ++n) {
    flag_mismatch += gpu.values[n].w != cpu->values[n].w;
    max_err = std::max(max_err, double(glm::length(gpu.values[n] - cpu->values[n])));
  }
  EXPECT_EQ(flag_mismatch, 0);  // 374,444 points without an owner before the fix
  // Float positions on a 378 mm grid (ulp 3e-5 mm) through tets of ~300 mm.
  EXPECT_LE(max_err, 1e-3);
}

}  // namespace
}  // namespace vpm

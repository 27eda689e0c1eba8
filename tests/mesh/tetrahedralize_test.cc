// Delaunay tetrahedralization of the proxy mesh (docs/ALGORITHM.md section 5).
#include "server/common/clock.h"
#include "server/mesh/tetrahedralize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

#include <gtest/gtest.h>

#include "server/mesh/tet_quality.h"
#include "tests/mesh/tet_mesh_test_util.h"

namespace vpm {
namespace {

using testing::LatticeMesh;
using testing::Positions;
using testing::RandomMesh;
using Tet = std::array<int32_t, 4>;

double TotalVolume(const ProxyMesh& mesh) {
  const auto p = Positions(mesh);
  double volume = 0.0;
  for (const Tet& t : mesh.tets) volume += SignedVolume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]);
  return volume;
}

// The tets as sorted index sets (orientation dropped), sorted.
std::vector<Tet> AsSets(const std::vector<Tet>& tets) {
  std::vector<Tet> sets = tets;
  for (Tet& t : sets) std::sort(t.begin(), t.end());
  std::sort(sets.begin(), sets.end());
  return sets;
}

void ExpectValidCover(const ProxyMesh& mesh, const glm::dvec3& extent) {
  const double box = extent.x * extent.y * extent.z;
  EXPECT_NEAR(TotalVolume(mesh), box, 1e-9 * box);
  EXPECT_EQ(CountInvertedTets(Positions(mesh), mesh.tets), 0);
  EXPECT_EQ(mesh.quality.removed_zero_volume, 0);
  EXPECT_GT(mesh.quality.min_dihedral_deg, 0.0);
  EXPECT_GT(mesh.quality.min_radius_ratio, 0.0);
  EXPECT_EQ(mesh.stats.tets, static_cast<int64_t>(mesh.tets.size()));
  // Every vertex is used (the lattice has no interior duplicates).
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const Tet& t : mesh.tets) {
    for (int32_t v : t) used[v] = 1;
  }
  EXPECT_EQ(std::count(used.begin(), used.end(), 1), static_cast<long>(used.size()));
}

TEST(Tetrahedralize, CoversTheBoxOnAFullLattice) {
  const glm::dvec3 extent(40.0, 30.0, 50.0);
  ProxyMesh mesh = LatticeMesh(5, extent);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  ASSERT_FALSE(mesh.tets.empty());
  ExpectValidCover(mesh, extent);
}

TEST(Tetrahedralize, TetsAreCanonicalAndSorted) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = LatticeMesh(4, extent);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  EXPECT_TRUE(std::is_sorted(mesh.tets.begin(), mesh.tets.end()));
  for (const Tet& t : mesh.tets) {
    EXPECT_LT(t[0], t[1]);
    EXPECT_LT(t[1], t[2]);
    EXPECT_LT(t[1], t[3]);
  }
}

TEST(Tetrahedralize, IsDeterministicAndIndependentOfInputOrder) {
  const glm::dvec3 extent(40.0, 30.0, 50.0);
  ProxyMesh first = LatticeMesh(5, extent);
  ProxyMesh second = first;
  ASSERT_TRUE(Tetrahedralize(first, extent).ok());
  ASSERT_TRUE(Tetrahedralize(second, extent).ok());
  EXPECT_EQ(first.tets, second.tets);

  // Shuffle: shuffled[n] = original[order[n]].
  std::vector<int32_t> order(first.vertices.size());
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), std::mt19937(7));
  ProxyMesh shuffled;
  for (int32_t v : order) shuffled.vertices.push_back(first.vertices[v]);
  ASSERT_TRUE(Tetrahedralize(shuffled, extent).ok());
  std::vector<Tet> relabelled = shuffled.tets;
  for (Tet& t : relabelled) {
    for (int32_t& v : t) v = order[v];
  }
  EXPECT_EQ(AsSets(relabelled), AsSets(first.tets));
}

TEST(Tetrahedralize, WorksAtTinyAndHugeScales) {
  for (double scale : {1e-6, 1.0, 1e6}) {
    SCOPED_TRACE(scale);
    const glm::dvec3 extent = glm::dvec3(4.0, 3.0, 5.0) * scale;
    ProxyMesh lattice = LatticeMesh(5, extent);
    ASSERT_TRUE(Tetrahedralize(lattice, extent).ok());
    ExpectValidCover(lattice, extent);
    ProxyMesh random = RandomMesh(200, extent, 3);
    ASSERT_TRUE(Tetrahedralize(random, extent).ok());
    ExpectValidCover(random, extent);
  }
}

TEST(Tetrahedralize, QualityOfALatticeIsReported) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = LatticeMesh(5, extent);
  ASSERT_TRUE(Tetrahedralize(mesh, extent).ok());
  const TetQuality q = MeasureTetQuality(mesh);
  EXPECT_DOUBLE_EQ(mesh.quality.min_dihedral_deg, q.min_dihedral_deg);
  EXPECT_DOUBLE_EQ(mesh.quality.mean_radius_ratio, q.mean_radius_ratio);
  EXPECT_LE(q.min_dihedral_deg, q.mean_min_dihedral_deg);
  EXPECT_LE(q.min_radius_ratio, q.mean_radius_ratio);
  EXPECT_LE(q.mean_radius_ratio, 1.0);
}

TEST(Tetrahedralize, RejectsDuplicatePositions) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = LatticeMesh(3, extent);
  mesh.vertices.push_back(mesh.vertices[4]);
  const Status status = Tetrahedralize(mesh, extent);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("vertices 4 and 35"), std::string::npos) << status;
  EXPECT_TRUE(mesh.tets.empty());
}

TEST(Tetrahedralize, RejectsTooFewOrCoplanarVertices) {
  ProxyMesh few;
  few.vertices.resize(3);
  few.vertices[1].position_mm = {1, 0, 0};
  few.vertices[2].position_mm = {0, 1, 0};
  EXPECT_EQ(Tetrahedralize(few, glm::dvec3(1.0)).code(), absl::StatusCode::kInvalidArgument);

  ProxyMesh flat;
  for (int n = 0; n < 9; ++n) {
    MeshVertex v;
    v.position_mm = {n % 3, n / 3, 0.0};
    flat.vertices.push_back(v);
  }
  const Status status = Tetrahedralize(flat, glm::dvec3(2.0));
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("coplanar"), std::string::npos) << status;
}

TEST(Tetrahedralize, RejectsNonFiniteAndOutsidePositions) {
  const glm::dvec3 extent(10.0);
  ProxyMesh nan = LatticeMesh(3, extent);
  nan.vertices[2].position_mm.y = std::nan("");
  EXPECT_NE(Tetrahedralize(nan, extent).message().find("non-finite"), std::string::npos);
  ProxyMesh outside = LatticeMesh(3, extent);
  outside.vertices[2].position_mm.z = 10.5;
  EXPECT_NE(Tetrahedralize(outside, extent).message().find("outside the box"), std::string::npos);
  ProxyMesh lattice = LatticeMesh(3, extent);
  EXPECT_FALSE(Tetrahedralize(lattice, glm::dvec3(10.0, 0.0, 10.0)).ok());
}

TEST(Tetrahedralize, RejectsAHullSmallerThanTheBox) {
  const glm::dvec3 extent(10.0);
  ProxyMesh mesh = LatticeMesh(3, extent);
  mesh.vertices.pop_back();  // a corner anchor
  const Status status = Tetrahedralize(mesh, extent);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("corners"), std::string::npos) << status;
}

// Timings for the report; the bound only catches gross regressions.
// Typical vertex counts, random and lattice (degenerate: cospherical
// points), each a valid cover of the box. How long they take is measured by
// bench/mesh_build_bench.cc, not here.
TEST(Tetrahedralize, TypicalVertexCountsGiveValidCovers) {
  const glm::dvec3 extent(255.0, 255.0, 180.0);
  struct Case {
    const char* name;
    ProxyMesh mesh;
  };
  std::vector<Case> cases;
  cases.push_back({"random 242+8", RandomMesh(242, extent, 1)});
  cases.push_back({"random 992+8", RandomMesh(992, extent, 2)});
  cases.push_back({"random 7992+8", RandomMesh(7992, extent, 3)});
  cases.push_back({"lattice 6^3+8", LatticeMesh(6, extent)});
  cases.push_back({"lattice 10^3+8", LatticeMesh(10, extent)});
  cases.push_back({"lattice 20^3+8", LatticeMesh(20, extent)});
  for (Case& c : cases) {
    ASSERT_TRUE(Tetrahedralize(c.mesh, extent).ok());
    std::printf("Tetrahedralize %-16s %6zu vertices %7zu tets  min dihedral %.2f deg\n", c.name,
                c.mesh.vertices.size(), c.mesh.tets.size(), c.mesh.quality.min_dihedral_deg);
    ExpectValidCover(c.mesh, extent);
  }
}

}  // namespace
}  // namespace vpm

// The organ under a grab point (organ_region.h): similar intensity,
// connected, within the bound, thin bridges to a neighbour of the same
// intensity cut by the opening.
#include "server/volume/organ_region.h"

#include <cmath>
#include <optional>
#include <random>

#include <gtest/gtest.h>

namespace vpm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// 64^3 voxels of 1 mm: air (-1000) around a body of fat (-100, radius 31 mm)
// with two organs of ~40 (a sphere of radius 12 mm at A and one of 10 mm at
// B, 27 mm apart) joined by a one-voxel bridge along x; deterministic noise
// of +-8. The window is then 3% of ~1,050 HU.
struct TwoOrgans {
  glm::dvec3 a{20.0, 32.0, 32.0}, b{47.0, 32.0, 32.0};
  std::optional<Volume> volume_storage;
  const Volume& volume() const { return *volume_storage; }
};

TwoOrgans MakeTwoOrgans() {
  TwoOrgans out;
  VolumeGeometry g;
  g.dims = {64, 64, 64};
  std::vector<float> values(g.voxel_count());
  uint64_t state = 99;
  for (int64_t k = 0; k < 64; ++k) {
    for (int64_t j = 0; j < 64; ++j) {
      for (int64_t i = 0; i < 64; ++i) {
        const glm::dvec3 p(i, j, k);
        float v = glm::distance(p, glm::dvec3(32.0)) <= 31.0 ? -100.0f : -1000.0f;
        if (glm::distance(p, out.a) <= 12.0) v = 40.0f;
        if (glm::distance(p, out.b) <= 10.0) v = 45.0f;
        if (j == 32 && k == 32 && i > 20 && i < 47) v = 40.0f;  // the bridge
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        v += static_cast<float>((state >> 33) % 17) - 8.0f;
        values[i + 64 * (j + 64 * k)] = v;
      }
    }
  }
  out.volume_storage = *Volume::Create(g, std::move(values));
  return out;
}

bool Holds(const OrganRegion& region, const glm::dvec3& p) {
  return region.Contains(int64_t(p.x), int64_t(p.y), int64_t(p.z));
}

// The algorithm on the voxels themselves (working_spacing_mm 0) in the
// tests below, the working grid after them.
OrganRegionParams OnVoxels() {
  OrganRegionParams params;
  params.working_spacing_mm = 0.0;
  return params;
}

TEST(OrganRegion, TakesTheOrganUnderTheSeedNotItsNeighbourAcrossAThinBridge) {
  const TwoOrgans scene = MakeTwoOrgans();
  auto region = GrowOrganRegion(scene.volume(), scene.a + glm::dvec3(3.0, 2.0, -1.0), OnVoxels());
  ASSERT_TRUE(region.ok()) << region.status();
  EXPECT_TRUE(Holds(*region, scene.a));
  EXPECT_FALSE(Holds(*region, scene.b));
  const double sphere_mm3 = 4.0 / 3.0 * kPi * 12.0 * 12.0 * 12.0;
  EXPECT_NEAR(region->volume_mm3, sphere_mm3, 0.15 * sphere_mm3);
  EXPECT_FALSE(region->reached_bound);
  // Its window keeps fat out: about +-31 around ~40.
  EXPECT_GT(region->window, 20.0f);
  EXPECT_LT(region->window, 60.0f);
}

// What the opening is for: without it the bridge carries the region into B.
TEST(OrganRegion, WithoutTheOpeningTheBridgeLeaks) {
  const TwoOrgans scene = MakeTwoOrgans();
  OrganRegionParams params = OnVoxels();
  params.opening_voxels = 0;
  auto region = GrowOrganRegion(scene.volume(), scene.a, params);
  ASSERT_TRUE(region.ok()) << region.status();
  EXPECT_TRUE(Holds(*region, scene.b));
}

TEST(OrganRegion, StaysWithinItsBound) {
  const TwoOrgans scene = MakeTwoOrgans();
  OrganRegionParams params = OnVoxels();
  params.max_radius_mm = 6.0;
  auto region = GrowOrganRegion(scene.volume(), scene.a, params);
  ASSERT_TRUE(region.ok()) << region.status();
  EXPECT_TRUE(region->reached_bound);
  for (int64_t linear : region->voxels) {
    const glm::dvec3 p(linear % 64, (linear / 64) % 64, linear / (64 * 64));
    EXPECT_LE(glm::distance(p, scene.a), 6.0 + 1e-9);
  }
}

TEST(OrganRegion, RejectsBadSeedsAndParameters) {
  const TwoOrgans scene = MakeTwoOrgans();
  EXPECT_EQ(GrowOrganRegion(scene.volume(), glm::dvec3(std::nan(""), 1.0, 1.0)).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(GrowOrganRegion(scene.volume(), glm::dvec3(-5.0, 1.0, 1.0)).status().code(),
            absl::StatusCode::kOutOfRange);
  OrganRegionParams params;
  params.max_radius_mm = 0.0;
  EXPECT_EQ(GrowOrganRegion(scene.volume(), scene.a, params).status().code(),
            absl::StatusCode::kInvalidArgument);
  // A bound of any finite size: past the volume it changes nothing.
  OrganRegionParams huge;
  huge.max_radius_mm = 1e300;
  OrganRegionParams whole;
  whole.max_radius_mm = 1000.0;
  auto huge_region = GrowOrganRegion(scene.volume(), scene.a, huge);
  ASSERT_TRUE(huge_region.ok()) << huge_region.status();
  EXPECT_EQ(huge_region->voxels, GrowOrganRegion(scene.volume(), scene.a, whole)->voxels);
  EXPECT_FALSE(huge_region->reached_bound);
  for (double spacing : {-1.0, std::nan(""), double(INFINITY)}) {
    OrganRegionParams bad;
    bad.working_spacing_mm = spacing;
    EXPECT_EQ(GrowOrganRegion(scene.volume(), scene.a, bad).status().code(),
              absl::StatusCode::kInvalidArgument);
  }
}

// Without the opening the region is the plain face-connected component of
// the accepted voxels through the seed: checked against a breadth-first
// flood written here, on noise thresholded into winding, branching shapes
// (runs along i that the fill must turn around in j and k), with the window
// and reference the region reports.
TEST(OrganRegion, WithoutTheOpeningEqualsABreadthFirstFlood) {
  VolumeGeometry g;
  g.dims = {40, 36, 32};
  g.spacing_mm = {0.8, 1.0, 1.3};
  std::vector<float> values(g.voxel_count());
  uint64_t state = 7;
  for (float& v : values) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    v = (state >> 33) % 100 < 62 ? 40.0f : -500.0f;  // about 62% "organ"
  }
  const Volume volume = *Volume::Create(g, std::move(values));
  OrganRegionParams params = OnVoxels();
  params.opening_voxels = 0;
  params.max_radius_mm = 14.0;
  const std::array<int64_t, 3> seed{20, 18, 16};
  const glm::dvec3 seed_mm = glm::dvec3(seed[0], seed[1], seed[2]) * g.spacing_mm;
  auto region = GrowOrganRegion(volume, seed_mm, params);
  ASSERT_TRUE(region.ok()) << region.status();

  const auto accept = [&](int64_t i, int64_t j, int64_t k) {
    if (i < 0 || j < 0 || k < 0 || i >= 40 || j >= 36 || k >= 32) return false;
    const glm::dvec3 d = (glm::dvec3(i, j, k) - glm::dvec3(seed[0], seed[1], seed[2])) * g.spacing_mm;
    return glm::dot(d, d) <= params.max_radius_mm * params.max_radius_mm &&
           std::abs(volume.At(i, j, k) - region->reference) <= region->window;
  };
  ASSERT_TRUE(accept(seed[0], seed[1], seed[2]));
  std::vector<uint8_t> seen(volume.geometry().voxel_count(), 0);
  std::vector<std::array<int64_t, 3>> queue{seed};
  seen[volume.LinearIndex(seed[0], seed[1], seed[2])] = 1;
  for (size_t q = 0; q < queue.size(); ++q) {
    const auto [i, j, k] = queue[q];
    const int64_t steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& st : steps) {
      const int64_t a = i + st[0], b = j + st[1], c = k + st[2];
      if (!accept(a, b, c) || seen[volume.LinearIndex(a, b, c)]) continue;
      seen[volume.LinearIndex(a, b, c)] = 1;
      queue.push_back({a, b, c});
    }
  }
  std::vector<int64_t> expected;
  for (int64_t x = 0; x < int64_t(seen.size()); ++x) {
    if (seen[x]) expected.push_back(x);
  }
  EXPECT_GT(expected.size(), 1000u);  // the shapes wind through much of the ball
  EXPECT_EQ(region->voxels, expected);
}

// Two organs of ~40 on 1 mm voxels joined by a contact three voxels thick
// and wide (a real contact at a fine reconstruction), with Gaussian noise of
// 5 (seeded): A a sphere of radius 15 mm at kContactA, B of 12 mm at
// kContactB, 36 mm apart.
constexpr glm::dvec3 kContactA(22.0, 32.0, 32.0), kContactB(58.0, 32.0, 32.0);

Volume ThickContact() {
  VolumeGeometry g;
  g.dims = {80, 64, 64};
  std::vector<float> values(g.voxel_count());
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 5.0f);
  for (int64_t k = 0, n = 0; k < 64; ++k)
    for (int64_t j = 0; j < 64; ++j)
      for (int64_t i = 0; i < 80; ++i, ++n) {
        const glm::dvec3 p(i, j, k);
        float v = glm::distance(p, glm::dvec3(40.0, 32.0, 32.0)) <= 38.0 ? -100.0f : -1000.0f;
        if (glm::distance(p, kContactA) <= 15.0 || glm::distance(p, kContactB) <= 12.0) v = 40.0f;
        if (std::abs(j - 32) <= 1 && std::abs(k - 32) <= 1 && i > 22 && i < 58) v = 40.0f;
        values[n] = v + noise(rng);
      }
  return *Volume::Create(g, std::move(values));
}

// On 1 mm voxels the opening's one voxel leaves a 3 mm contact standing and
// the region runs into B; on the working grid (3 mm cells) the contact is a
// cell thin and the opening cuts it.
TEST(OrganRegion, TheWorkingGridCutsAContactOfAFewMillimetres) {
  const Volume volume = ThickContact();
  auto on_voxels = GrowOrganRegion(volume, kContactA, OnVoxels());
  ASSERT_TRUE(on_voxels.ok()) << on_voxels.status();
  EXPECT_TRUE(Holds(*on_voxels, kContactB));
  auto region = GrowOrganRegion(volume, kContactA);
  ASSERT_TRUE(region.ok()) << region.status();
  EXPECT_EQ(region->grid.factor, (std::array<int64_t, 3>{3, 3, 3}));
  EXPECT_TRUE(Holds(*region, kContactA));
  EXPECT_FALSE(Holds(*region, kContactB));
  const double sphere_mm3 = 4.0 / 3.0 * kPi * 15.0 * 15.0 * 15.0;
  EXPECT_NEAR(region->volume_mm3, sphere_mm3, 0.3 * sphere_mm3);
}

}  // namespace
}  // namespace vpm

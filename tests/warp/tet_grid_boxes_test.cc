// Grid boxes of deformed tets and the box-meeting query of incremental
// backward-map updates.
#include "server/warp/tet_grid_boxes.h"

#include <random>
#include <utility>

#include <gtest/gtest.h>

namespace vpm {
namespace {

// Barycentric weights of p in the tet, in double.
glm::dvec4 Weights(const std::array<glm::dvec3, 4>& c, const glm::dvec3& p) {
  const glm::dvec3 w = glm::inverse(glm::dmat3(c[1] - c[0], c[2] - c[0], c[3] - c[0])) * (p - c[0]);
  return {1.0 - w.x - w.y - w.z, w.x, w.y, w.z};
}

bool Inside(const GridBox& box, const glm::ivec3& g) {
  return glm::all(glm::greaterThanEqual(g, box.lo)) && glm::all(glm::lessThanEqual(g, box.hi));
}

TEST(TetGridBox, HoldsEveryPointWithWeightsAboveMinusEps) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 45.0);
  const std::array<int64_t, 3> dims{21, 17, 13};
  const glm::dvec3 step(2.0, 2.5, 3.0);
  for (double eps : {0.0, 1e-5, 0.05}) {
    for (int n = 0; n < 200; ++n) {
      const std::array<glm::dvec3, 4> c = {
          glm::dvec3(u(rng), u(rng), u(rng)), glm::dvec3(u(rng), u(rng), u(rng)),
          glm::dvec3(u(rng), u(rng), u(rng)), glm::dvec3(u(rng), u(rng), u(rng))};
      const GridBox box = TetGridBox(c, step, dims, eps);
      for (int z = 0; z < dims[2]; ++z) {
        for (int y = 0; y < dims[1]; ++y) {
          for (int x = 0; x < dims[0]; ++x) {
            const glm::dvec4 w = Weights(c, glm::dvec3(x, y, z) * step);
            if (glm::all(glm::greaterThanEqual(w, glm::dvec4(-eps)))) {
              ASSERT_TRUE(Inside(box, {x, y, z})) << "eps " << eps << " tet " << n;
            }
          }
        }
      }
      for (int a = 0; a < 3; ++a) {
        if (box.empty()) break;
        EXPECT_GE(box.lo[a], 0);
        EXPECT_LT(box.hi[a], dims[a]);
      }
    }
  }
}

TEST(TetGridBox, IsEmptyForATetOutsideTheGrid) {
  const std::array<glm::dvec3, 4> c = {glm::dvec3(100, 0, 0), glm::dvec3(110, 0, 0),
                                       glm::dvec3(100, 10, 0), glm::dvec3(100, 0, 10)};
  EXPECT_TRUE(TetGridBox(c, {1, 1, 1}, {10, 10, 10}, 1e-5).empty());
}

// Brute force against the binned search, on few and many region boxes,
// small and large (a large box spans many of the search's cells).
TEST(TetsMeetingBoxes, MatchesBruteForce) {
  std::mt19937 rng(7);
  for (const auto& [region_count, max_len] : {std::pair{30, 8}, std::pair{300, 8},
                                              std::pair{1, 30}, std::pair{200, 40}}) {
    std::uniform_int_distribution<int> u(0, 40), len(0, max_len);
    const int overshoot = max_len + 1;  // a named copy: clang 14 captures no structured binding
    auto random_box = [&] {
      GridBox b;
      // One draw per statement: the order of a call's arguments is
      // unspecified, and the boxes must not depend on the compiler.
      b.lo = {u(rng), u(rng), u(rng)};  // a braced list: left to right
      const glm::ivec3 extent = {len(rng), len(rng), len(rng)};
      const bool inverted = u(rng) < 3;
      b.hi = b.lo + extent - (inverted ? overshoot : 0);
      return b;
    };
    std::vector<GridBox> tets(500), region(region_count);
    for (auto& b : tets) b = random_box();
    for (auto& b : region) b = random_box();
    std::vector<int32_t> expected;
    for (size_t t = 0; t < tets.size(); ++t) {
      for (const GridBox& r : region) {
        if (!tets[t].empty() && !r.empty() && glm::all(glm::lessThanEqual(tets[t].lo, r.hi)) &&
            glm::all(glm::lessThanEqual(r.lo, tets[t].hi))) {
          expected.push_back(static_cast<int32_t>(t));
          break;
        }
      }
    }
    EXPECT_GT(expected.size(), 10u) << region_count << " region boxes";
    EXPECT_LT(expected.size(), tets.size()) << region_count << " region boxes";
    EXPECT_EQ(TetsMeetingBoxes(tets, region), expected) << region_count << " region boxes";
  }
}

TEST(TetsMeetingBoxes, IsEmptyForAnEmptyRegion) {
  const std::vector<GridBox> tets = {GridBox{{0, 0, 0}, {3, 3, 3}}};
  EXPECT_TRUE(TetsMeetingBoxes(tets, {}).empty());
  EXPECT_TRUE(TetsMeetingBoxes(tets, std::vector<GridBox>{GridBox{}}).empty());
}

}  // namespace
}  // namespace vpm

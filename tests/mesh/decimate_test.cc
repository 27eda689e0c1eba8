#include "server/mesh/decimate.h"

#include <random>
#include <set>

#include <gtest/gtest.h>

#include "server/mesh/indexed_min_heap.h"
#include "server/mesh/lookahead_min_queue.h"
#include "server/mesh/monotone_min_queue.h"
#include "server/mesh/lattice.h"
#include "server/mesh/lattice_costs.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

DecimationInput LatticeInput(std::array<int64_t, 3> g, double step, uint32_t seed) {
  DecimationInput in;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int64_t c = 0; c < g[2]; ++c)
    for (int64_t b = 0; b < g[1]; ++b)
      for (int64_t a = 0; a < g[0]; ++a) {
        in.positions.emplace_back(a * step, b * step * 1.1, c * step * 0.9);
        // A quarter of the vertices in "air" (Ci = 0) makes exact ties common.
        in.ci.push_back(u(rng) < 0.25 ? 0.0 : u(rng));
        in.cg.push_back(u(rng));
      }
  return in;
}

TEST(IndexedMinHeap, PopsInCostThenIdOrderUnderUpdates) {
  IndexedMinHeap heap({3.0, 1.0, 2.0, 1.0, 5.0});
  heap.Update(4, 0.5);
  heap.Update(1, 4.0);
  std::vector<int64_t> order;
  while (!heap.empty()) order.push_back(heap.Pop());
  EXPECT_EQ(order, (std::vector<int64_t>{4, 3, 2, 0, 1}));
}

// Against an ordered set of (cost, item): random costs from few values (so
// ties are common), random raises and lowers, pops interleaved, sizes around
// the 4-ary heap's level boundaries.
TEST(IndexedMinHeap, MatchesAnOrderedSetUnderRandomUpdatesAndPops) {
  std::mt19937 rng(11);
  for (int n : {0, 1, 2, 4, 5, 6, 21, 22, 85, 86, 1000}) {
    std::uniform_int_distribution<int> value(0, 9);
    std::vector<double> costs(n);
    for (auto& c : costs) c = value(rng) * 0.5;
    IndexedMinHeap heap(costs);
    std::set<std::pair<double, int64_t>> reference;
    for (int i = 0; i < n; ++i) reference.emplace(costs[i], i);
    while (!reference.empty()) {
      ASSERT_EQ(heap.size(), static_cast<int64_t>(reference.size()));
      ASSERT_EQ(heap.top(), reference.begin()->second) << "n " << n;
      ASSERT_EQ(heap.top_cost(), reference.begin()->first);
      if (rng() % 3 == 0) {
        EXPECT_EQ(heap.Pop(), reference.begin()->second);
        reference.erase(reference.begin());
        continue;
      }
      // Update a random contained item up or down.
      auto it = std::next(reference.begin(), rng() % reference.size());
      const int64_t item = it->second;
      const double cost = value(rng) * 0.5;
      reference.erase(it);
      reference.emplace(cost, item);
      heap.Update(item, cost);
      ASSERT_TRUE(heap.contains(item));
      ASSERT_EQ(heap.cost(item), cost);
    }
    EXPECT_TRUE(heap.empty());
  }
}

// The monotone queue against an ordered set: each step pops the smallest key
// and, two times in three, pushes it back raised (as step 2 refreshes a
// stale key) or pushes a new item at or above it; costs from few values
// (ties common), zeros and -0.0 among them.
TEST(MonotoneMinQueue, PopsWhatAnOrderedSetPopsUnderMonotonePushes) {
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> value(0, 7);
  for (int n : {1, 2, 33, 500, 3000}) {
    MonotoneMinQueue queue;
    std::set<std::pair<double, int32_t>> reference;
    int32_t next_item = 0;
    for (; next_item < n; ++next_item) {
      const double cost = next_item % 5 == 0 ? -0.0 : value(rng) * 0.25;
      queue.Push(cost, next_item);
      reference.emplace(cost + 0.0, next_item);
    }
    while (!reference.empty()) {
      ASSERT_EQ(queue.size(), static_cast<int64_t>(reference.size()));
      const auto top = queue.Top();
      ASSERT_EQ(top.item, reference.begin()->second) << "n " << n;
      ASSERT_EQ(top.cost, reference.begin()->first);
      queue.Pop();
      reference.erase(reference.begin());
      const int action = static_cast<int>(rng() % 3);
      if (action == 0 && next_item < 4 * n) {  // a raised key for the same item
        const double cost = top.cost + value(rng) * 0.25;
        queue.Push(cost, top.item);
        reference.emplace(cost, top.item);
      } else if (action == 1 && next_item < 4 * n) {  // a new item, not below the last key
        const double cost = top.cost + value(rng) * 0.25;
        queue.Push(cost, next_item);
        reference.emplace(cost, next_item);
        ++next_item;
      }
    }
    EXPECT_TRUE(queue.empty());
  }
}

// The same scenario through the lookahead queue, whose pops come in runs
// (sorted buckets of at most MonotoneMinQueue::kMaxRun keys) and whose
// raised keys may land in its window: what it pops, and the keys it shows
// ahead, are what an ordered set holds at that moment.
TEST(LookaheadMinQueue, PopsAndShowsAheadWhatAnOrderedSetHolds) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> value(0, 7);
  for (int n : {1, 2, 33, 500, 3000, 20000}) {
    LookaheadMinQueue queue;
    std::set<std::pair<double, int32_t>> reference;
    int32_t next_item = 0;
    for (; next_item < n; ++next_item) {
      const double cost = next_item % 5 == 0 ? -0.0 : value(rng) * (n > 3000 ? 1e-3 : 0.25);
      queue.Push(cost, next_item);
      reference.emplace(cost + 0.0, next_item);
    }
    while (!reference.empty()) {
      ASSERT_EQ(queue.size(), static_cast<int64_t>(reference.size()));
      auto expected = reference.begin();
      for (size_t k = 0; k < 6; ++k, ++expected) {
        const LookaheadMinQueue::Entry* ahead = queue.Ahead(k);
        if (expected == reference.end()) {
          ASSERT_EQ(ahead, nullptr);
          break;
        }
        ASSERT_NE(ahead, nullptr);
        ASSERT_EQ(ahead->item, expected->second) << "n " << n << " k " << k;
        ASSERT_EQ(ahead->cost, expected->first);
      }
      const auto top = queue.Top();
      ASSERT_EQ(top.item, reference.begin()->second) << "n " << n;
      queue.Pop();
      reference.erase(reference.begin());
      const int action = static_cast<int>(rng() % 3);
      const double step = value(rng) * (rng() % 2 == 0 ? 0.25 : 1e-6);
      if (action == 0 && next_item < 4 * n) {  // a raised key for the same item
        queue.Push(top.cost + step, top.item);
        reference.emplace(top.cost + step, top.item);
      } else if (action == 1 && next_item < 4 * n) {  // a new item, not below the last key
        queue.Push(top.cost + step, next_item);
        reference.emplace(top.cost + step, next_item);
        ++next_item;
      }
    }
    EXPECT_TRUE(queue.empty());
  }
}

class DecimateModes : public ::testing::TestWithParam<DensityMode> {};

TEST_P(DecimateModes, FastAndNaiveKeepTheSameVertices) {
  const DecimationInput in = LatticeInput({14, 12, 10}, 5.0, 7);
  const DecimationParams p{.target = 120, .radius_mm = 2.0 * 5.0 * 1.1, .density_mode = GetParam()};
  auto fast = DecimateFast(in, p);
  auto naive = DecimateNaive(in, p);
  ASSERT_TRUE(fast.ok() && naive.ok());
  EXPECT_EQ(fast->kept.size(), 112u);  // target counts the 8 anchors
  EXPECT_EQ(fast->kept, naive->kept);
  EXPECT_EQ(fast->removal_order, naive->removal_order);
  EXPECT_EQ(fast->kept_cost, naive->kept_cost);
  EXPECT_EQ(fast->d0, naive->d0);
}

// Scattered (not lattice) points: the grid's buckets then hold uneven
// counts, some none, and neighbour lists differ from vertex to vertex.
TEST_P(DecimateModes, FastAndNaiveAgreeOnScatteredPoints) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  DecimationInput in;
  for (int i = 0; i < 900; ++i) {
    in.positions.emplace_back(60.0 * u(rng), 40.0 * u(rng) * u(rng), 25.0 * u(rng));
    in.ci.push_back(u(rng) < 0.3 ? 0.0 : u(rng));
    in.cg.push_back(u(rng));
  }
  const DecimationParams p{.target = 100, .radius_mm = 7.5, .density_mode = GetParam()};
  auto fast = DecimateFast(in, p);
  auto naive = DecimateNaive(in, p);
  ASSERT_TRUE(fast.ok() && naive.ok());
  EXPECT_EQ(fast->removal_order, naive->removal_order);
  EXPECT_EQ(fast->kept_cost, naive->kept_cost);
  EXPECT_EQ(fast->d0, naive->d0);
}

// The neighbour search splits the grid's buckets between threads; each
// vertex's list and density must not depend on the split. The lattice has
// enough points for four threads (at least kMinPointsPerSearchThread each).
TEST_P(DecimateModes, ThreadCountDoesNotChangeTheResult) {
  const DecimationInput in = LatticeInput({48, 40, 36}, 1.0, 13);
  ASSERT_GE(static_cast<int64_t>(in.positions.size()), 4 * kMinPointsPerSearchThread);
  const DecimationParams one{.target = 500, .radius_mm = 2.0, .density_mode = GetParam(),
                             .threads = 1};
  auto reference = DecimateFast(in, one);
  ASSERT_TRUE(reference.ok());
  for (int threads : {2, 3, 4, 0}) {
    DecimationParams p = one;
    p.threads = threads;
    auto r = DecimateFast(in, p);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->removal_order, reference->removal_order) << threads << " threads";
    EXPECT_EQ(r->kept, reference->kept) << threads << " threads";
    EXPECT_EQ(r->kept_cost, reference->kept_cost) << threads << " threads";
    EXPECT_EQ(r->d0, reference->d0) << threads << " threads";
  }
}

INSTANTIATE_TEST_SUITE_P(BothModes, DecimateModes,
                         ::testing::Values(DensityMode::kSpread, DensityMode::kPaper));

TEST(Decimate, TiesGoToTheSmallerId) {
  DecimationInput in = LatticeInput({6, 6, 6}, 1.0, 3);
  std::fill(in.ci.begin(), in.ci.end(), 0.0);  // every cost 0
  auto r = DecimateFast(in, {.target = 8 + 200, .radius_mm = 2.0});
  ASSERT_TRUE(r.ok());
  for (int64_t n = 0; n < 16; ++n) EXPECT_EQ(r->removal_order[n], n);
}

TEST(Decimate, SpreadModeRemovesFromCrowdsAndPaperModeFromTheEdges) {
  // Uniform image terms: only the spreading term decides. In a finite lattice
  // the border vertices have fewer neighbours (lower density).
  DecimationInput in = LatticeInput({10, 10, 10}, 1.0, 1);
  std::fill(in.ci.begin(), in.ci.end(), 1.0);
  std::fill(in.cg.begin(), in.cg.end(), 0.0);
  auto spread = DecimateFast(in, {.target = 8 + 990, .radius_mm = 2.0,
                                  .density_mode = DensityMode::kSpread});
  auto paper = DecimateFast(in, {.target = 8 + 990, .radius_mm = 2.0,
                                 .density_mode = DensityMode::kPaper});
  ASSERT_TRUE(spread.ok() && paper.ok());
  // Steps are 1, 1.1 and 0.9 mm with R = 2: a full neighbourhood reaches one
  // step along x and y and two along z.
  auto is_interior = [](int64_t id) {
    const int64_t a = id % 10, b = (id / 10) % 10, c = id / 100;
    return a >= 1 && a <= 8 && b >= 1 && b <= 8 && c >= 2 && c <= 7;
  };
  EXPECT_TRUE(is_interior(spread->removal_order.front()));   // crowded goes first
  EXPECT_EQ(paper->removal_order.front(), 0);                 // a corner: least dense
}

TEST(Decimate, DensityMatchesTheDefinition) {
  const DecimationInput in = LatticeInput({4, 4, 4}, 1.0, 9);
  auto r = DecimateNaive(in, {.target = 8 + 64, .radius_mm = 1.5});
  ASSERT_TRUE(r.ok());
  // Interior vertex: 6 at distance 1, 12 at sqrt(2)*... with y scaled 1.1 and z 0.9.
  double expected_max = 0.0;
  for (size_t v = 0; v < in.positions.size(); ++v) {
    double dens = 0;
    for (size_t u = 0; u < in.positions.size(); ++u) {
      const double d = glm::distance(in.positions[u], in.positions[v]);
      if (u != v && d < 1.5) dens += 1.0 / d;
    }
    expected_max = std::max(expected_max, dens);
  }
  EXPECT_NEAR(r->d0, expected_max, 1e-12);
}

TEST(Decimate, RejectsBadParameters) {
  const DecimationInput in = LatticeInput({4, 4, 4}, 1.0, 9);
  EXPECT_FALSE(DecimateFast(in, {.target = 7, .radius_mm = 2}).ok());
  EXPECT_FALSE(DecimateFast(in, {.target = 8 + 65, .radius_mm = 2}).ok());
  EXPECT_FALSE(DecimateFast(in, {.target = 20, .radius_mm = 0}).ok());
  EXPECT_FALSE(DecimateFast(in, {.target = 20, .wg = -1, .radius_mm = 2}).ok());
  EXPECT_FALSE(DecimateFast(in, {.target = 20, .radius_mm = 2, .threads = -1}).ok());
  DecimationInput bad = in;
  bad.ci[5] = std::nan("");
  EXPECT_FALSE(DecimateFast(bad, {.target = 20, .radius_mm = 2}).ok());
}

TEST(Decimate, FastMatchesNaiveOnRealImageCosts) {
  const Volume v = testing::MakeBodyVolume();
  auto lattice = Lattice::Create(v.geometry(), {12, 10, 8});
  ASSERT_TRUE(lattice.ok());
  const LatticeCosts costs = EvaluateLatticeCostsCpu(v, *lattice, TransferFunction::CtSoftTissue());
  DecimationInput in{.ci = costs.ci_cell, .cg = NormalizeGradientCost(costs.g_cell)};
  for (int64_t id = 0; id < lattice->size(); ++id) in.positions.push_back(lattice->Position(id));
  const DecimationParams p{.target = 100, .radius_mm = 2.0 * lattice->h_mm()};
  auto fast = DecimateFast(in, p);
  auto naive = DecimateNaive(in, p);
  ASSERT_TRUE(fast.ok() && naive.ok());
  EXPECT_EQ(fast->kept, naive->kept);
}

}  // namespace
}  // namespace vpm

// Step 1 in native rows (EvaluateLatticeCostsRows, what lavapipe devices run)
// against the double-precision reference, for float and int16 volumes (with
// an offset), lattices coarser and finer than the voxels, a TF with a step,
// and one and several threads; and a cancelled evaluation.
#include <algorithm>
#include <atomic>
#include <cmath>

#include <gtest/gtest.h>

#include "server/mesh/lattice_costs.h"
#include "server/mesh/lattice_costs_rows.h"
#include "tests/mesh/mesh_test_volumes.h"
#include "tests/volume/int16_twin.h"

namespace vpm {
namespace {

// Tolerances: Ci within 1e-6 absolute (TF per voxel rounded to float, sums in
// double); g within 1e-6 of the largest g (|grad|^2 in float from exact
// differences). The point footprint is the reference's own code: equal.
void ExpectMatchesReference(const Volume& v, const Lattice& lattice, const TransferFunction& tf,
                            int threads) {
  auto evaluated = EvaluateLatticeCostsRows(v, lattice, tf, threads);
  ASSERT_TRUE(evaluated.ok()) << evaluated.status();
  const LatticeCosts& rows = *evaluated;
  const LatticeCosts cpu = EvaluateLatticeCostsCpu(v, lattice, tf);
  ASSERT_EQ(rows.ci_cell.size(), size_t(lattice.size()));
  for (Footprint f : {Footprint::kCell, Footprint::kPoint}) {
    const double g_max = *std::max_element(cpu.g(f).begin(), cpu.g(f).end());
    ASSERT_GT(g_max, 0.0);
    for (int64_t id = 0; id < lattice.size(); ++id) {
      const std::string where = StrCat(FootprintName(f), " id ", id, " threads ", threads,
                                       " tf ", tf.ToString());
      if (f == Footprint::kPoint) {
        ASSERT_EQ(rows.ci(f)[id], cpu.ci(f)[id]) << where;
        ASSERT_EQ(rows.g(f)[id], cpu.g(f)[id]) << where;
      } else {
        ASSERT_NEAR(rows.ci(f)[id], cpu.ci(f)[id], 1e-6) << where;
        ASSERT_NEAR(rows.g(f)[id], cpu.g(f)[id], 1e-6 * g_max) << where;
      }
    }
  }
}

TEST(LatticeCostsRows, MatchesCpuReferenceForBothFootprints) {
  const Volume body = testing::MakeBodyVolume({50, 41, 33}, {0.9, 1.2, 1.6});
  const auto step_tf = TransferFunction::Create({{-300, 0}, {0, 0.5}, {150, 0.5}, {150, 1.0}});
  ASSERT_TRUE(step_tf.ok()) << step_tf.status();
  const auto int16 = testing::MakeInt16Twin(body, 1000).int16;  // stored = value - 1000
  ASSERT_TRUE(int16.voxels().is_int16());
  ASSERT_NE(int16.voxels().int16_offset(), 0);
  for (const Volume* v : {&body, &int16}) {
    SCOPED_TRACE(v->voxels().is_int16() ? "int16" : "float");
    for (const std::array<int64_t, 3> grid :
         {std::array<int64_t, 3>{7, 9, 5}, std::array<int64_t, 3>{50, 41, 33},
          std::array<int64_t, 3>{1, 1, 1}}) {
      auto lattice = Lattice::Create(v->geometry(), grid);
      ASSERT_TRUE(lattice.ok());
      for (const TransferFunction& tf : {TransferFunction::CtSoftTissue(), *step_tf}) {
        for (int threads : {1, 3}) ExpectMatchesReference(*v, *lattice, tf, threads);
      }
    }
  }
}

// A volume one voxel thick along x: the clamped neighbours of the row ends
// are the same voxel.
TEST(LatticeCostsRows, OneVoxelWideRows) {
  const Volume thin = testing::MakeBodyVolume({1, 12, 9}, {1.0, 1.0, 1.0});
  auto lattice = Lattice::Create(thin.geometry(), {1, 4, 3});
  ASSERT_TRUE(lattice.ok()) << lattice.status();
  auto evaluated = EvaluateLatticeCostsRows(thin, *lattice, TransferFunction::CtSoftTissue(), 2);
  ASSERT_TRUE(evaluated.ok()) << evaluated.status();
  const LatticeCosts& rows = *evaluated;
  const LatticeCosts cpu = EvaluateLatticeCostsCpu(thin, *lattice, TransferFunction::CtSoftTissue());
  for (int64_t id = 0; id < lattice->size(); ++id) {
    EXPECT_NEAR(rows.ci_cell[id], cpu.ci_cell[id], 1e-6) << id;
    EXPECT_NEAR(rows.g_cell[id], cpu.g_cell[id], 1e-6 * (1.0 + cpu.g_cell[id])) << id;
  }
}

}  // namespace
}  // namespace vpm

namespace vpm {
namespace {

// A cancellation stops the threads before their next cell layer: the poll
// that fails is about the fourth of eight layers', so far fewer than the
// eight polls of a whole evaluation happen, and its status comes back.
TEST(LatticeCostsRows, ACancelledEvaluationStopsBeforeTheNextLayer) {
  const Volume v = testing::MakeBodyVolume({40, 40, 40}, {1.0, 1.0, 1.0});
  auto lattice = Lattice::Create(v.geometry(), {8, 8, 8});
  ASSERT_TRUE(lattice.ok()) << lattice.status();
  std::atomic<int> polls{0};
  const CancelToken cancel([&]() -> Status {
    return ++polls > 3 ? absl::CancelledError("the call was cancelled") : absl::OkStatus();
  });
  auto costs = EvaluateLatticeCostsRows(v, *lattice, TransferFunction::CtSoftTissue(), 2, cancel);
  EXPECT_EQ(costs.status().code(), absl::StatusCode::kCancelled) << costs.status();
  EXPECT_LE(polls.load(), 6);
}

}  // namespace
}  // namespace vpm

// The per-event work bound (event_budget.h, SolverOptions::
// event_newton_budget): no Drag spends more Newton iterations than its
// budget, a drag that needs more stops at a feasible fraction and carries the
// rest, repeated events reach the target exactly, and the settled state is
// the unbounded solve's, with no tet inverted.
#include "server/fem/event_budget.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "server/common/status.h"

#include "server/fem/fem_model.h"
#include "tests/fem/fem_test_meshes.h"
#include "tests/fem/pinned_phantom_mesh.h"
#include "tests/mesh/mesh_test_volumes.h"

namespace vpm {
namespace {

TEST(FemEventBudget, UnboundedAlwaysHasRoom) {
  const EventBudget budget;
  EXPECT_TRUE(budget.RoomForLoadStep(1000, 2));
  EXPECT_EQ(budget.IterationsFor(1000, 30), 30);
}

TEST(FemEventBudget, RoomLeavesTheStopIterations) {
  const EventBudget budget(12, 4);
  // A partial load step (2 iterations) and the 4 stop iterations after it.
  EXPECT_TRUE(budget.RoomForLoadStep(6, 2));
  EXPECT_FALSE(budget.RoomForLoadStep(7, 2));
  EXPECT_EQ(budget.IterationsFor(6, 30), 6);
  EXPECT_EQ(budget.IterationsFor(6, 2), 2);
}

TEST(FemEventBudget, LoadStepsCarryOnlyTowardsTheSameUnreachedLoad) {
  EventBudget budget(8, 2);
  const std::vector<int32_t> constrained = {0, 4};
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(6);
  prescribed[4] = 1.5;
  const Eigen::VectorXd force = Eigen::VectorXd::Zero(6);
  budget.BeginSolve(prescribed, force, constrained, Eigen::VectorXd::Zero(6));
  budget.CountLoadStep();
  budget.CountLoadStep();
  budget.EndSolve(/*reached=*/false);
  // The same target again (a settle pass): the count goes on.
  budget.BeginSolve(prescribed, force, constrained, Eigen::VectorXd::Zero(6));
  EXPECT_EQ(budget.load_steps(), 2);
  budget.CountLoadStep();
  budget.EndSolve(false);
  // A value on a DOF that is not constrained does not make a new load.
  prescribed[1] = 7.0;
  budget.BeginSolve(prescribed, force, constrained, Eigen::VectorXd::Zero(6));
  EXPECT_EQ(budget.load_steps(), 3);
  budget.EndSolve(false);
  // The pointer moved: a new load.
  prescribed[4] = 1.6;
  budget.BeginSolve(prescribed, force, constrained, Eigen::VectorXd::Zero(6));
  EXPECT_EQ(budget.load_steps(), 0);
  budget.CountLoadStep();
  budget.EndSolve(/*reached=*/true);
  // Reached: nothing is carried, even towards the same target.
  budget.BeginSolve(prescribed, force, constrained, Eigen::VectorXd::Zero(6));
  EXPECT_EQ(budget.load_steps(), 0);
}

TEST(FemEventBudget, BudgetBelowAPartialLoadStepIsInvalidArgument) {
  const Volume volume = testing::MakeBodyVolume();
  auto mesh = testing::CentreRefinedMesh(volume);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  FemOptions options;
  options.solver.event_newton_budget = options.solver.intermediate_newton_iterations +
                                       options.solver.event_stop_newton_iterations - 1;
  EXPECT_EQ(FemModel::Create(*mesh, volume.geometry().extent_mm(), options).status().code(),
            absl::StatusCode::kInvalidArgument);
  options.solver.event_newton_budget = 0;  // unbounded
  EXPECT_TRUE(FemModel::Create(*mesh, volume.geometry().extent_mm(), options).ok());
  options.solver.event_newton_budget = 8;
  options.solver.event_stop_newton_iterations = -1;
  EXPECT_EQ(FemModel::Create(*mesh, volume.geometry().extent_mm(), options).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// The barrier test's drag (inversion_barrier_test.cc): the handles at the
// centre of the body volume dragged 1.5 h, which the barrier takes in
// several load steps and without inverting a tet.
struct BarrierDrag {
  Volume volume = testing::MakeBodyVolume();
  ProxyMesh mesh;
  glm::dvec3 point{0.0};
  glm::dvec3 drag{0.0};
};

BarrierDrag MakeBarrierDrag() {
  BarrierDrag d;
  auto mesh = testing::CentreRefinedMesh(d.volume);
  EXPECT_TRUE(mesh.ok()) << mesh.status();
  if (mesh.ok()) d.mesh = *std::move(mesh);
  d.point = d.volume.geometry().extent_mm() * 0.5;
  d.drag = glm::dvec3(1.5 * d.mesh.stats.h_mm, 0.0, 0.0);
  return d;
}

struct DragResult {
  std::vector<glm::dvec3> displacements;  // #V, mm
  std::vector<int32_t> handles;
  int64_t inverted = -1;
  int events = 0;        // Drag calls, then Settle calls
  int short_events = 0;  // events that stopped short of their offset
  bool forced = false;
};

// Drags `d` in `increments` events, then settles (at most max_settle more
// events), expecting every event within `budget` Newton iterations.
DragResult RunDrag(const BarrierDrag& d, SolverOptions solver, int increments, int max_settle) {
  DragResult out;
  FemOptions options;
  options.solver = solver;
  auto model = FemModel::Create(d.mesh, d.volume.geometry().extent_mm(), options);
  EXPECT_TRUE(model.ok()) << model.status();
  if (!model.ok()) return out;
  const auto grab = model->Grab(d.point, d.mesh.stats.h_mm);
  EXPECT_TRUE(grab.ok()) << grab.status();
  if (!grab.ok()) return out;
  out.handles = grab->handles;
  const auto check = [&](const Result<SolveStats>& stats) {
    EXPECT_TRUE(stats.ok()) << stats.status();
    if (!stats.ok()) return;
    ++out.events;
    if (solver.event_newton_budget > 0) {
      EXPECT_LE(stats->newton_iterations, solver.event_newton_budget) << "event " << out.events;
    }
    EXPECT_GE(stats->target_fraction, 0.0);
    EXPECT_LE(stats->target_fraction, 1.0);
    EXPECT_EQ(stats->target_fraction == 1.0, stats->remaining_mm == 0.0);
    if (stats->target_fraction < 1.0) {
      ++out.short_events;
      EXPECT_FALSE(stats->converged);
    }
    out.forced |= stats->forced_inversion;
  };
  for (int i = 1; i <= increments; ++i) {
    check(model->Drag(d.drag * (static_cast<double>(i) / increments)));
  }
  for (int i = 0; i < max_settle && !model->settled(); ++i) check(model->Settle());
  EXPECT_TRUE(model->settled()) << "not settled after " << max_settle << " more events";
  out.displacements = model->Displacements();
  out.inverted = model->CountInvertedTets();
  return out;
}

double LargestDistance(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
  double largest = 0.0;
  for (size_t v = 0; v < a.size(); ++v) largest = std::max(largest, glm::distance(a[v], b[v]));
  return largest;
}

// Converged settings (as in measuring) so that the comparison is between
// equilibria, not between solver paths.
SolverOptions Converged(int budget) {
  SolverOptions solver;
  solver.update_tolerance = 1e-8;
  solver.cg_tolerance = 1e-3;
  solver.max_newton_iterations = 200;
  solver.max_load_steps = 64;
  solver.event_newton_budget = budget;
  return solver;
}

// Equilibria of the same drag agree to this, mm (the drag is 1.5 h, ~30 mm;
// both solves stop at 1e-8 of the motion per update).
constexpr double kSettledToleranceMm = 1e-4;

TEST(FemEventBudget, DragAtOnceStopsShortCarriesTheRestAndSettlesToTheUnboundedSolve) {
  const BarrierDrag d = MakeBarrierDrag();
  ASSERT_FALSE(d.mesh.vertices.empty());
  const DragResult unbounded = RunDrag(d, Converged(0), 1, 0);
  ASSERT_EQ(unbounded.events, 1);
  ASSERT_FALSE(unbounded.forced);
  EXPECT_EQ(unbounded.inverted, 0);
  // The interactive bound, and the least one (one partial load step per
  // event: the rest carried event after event).
  for (int budget : {kInteractiveEventNewtonBudget, 6}) {
    SCOPED_TRACE(StrCat("budget ", budget));
    const DragResult bounded = RunDrag(d, Converged(budget), 1, 60);
    EXPECT_GT(bounded.short_events, 0) << "the drag no longer needs more than one event";
    EXPECT_FALSE(bounded.forced);
    // The handles reached the drag exactly, and nothing inverted.
    for (int32_t v : bounded.handles) {
      EXPECT_NEAR(glm::distance(bounded.displacements[v], d.drag), 0.0, 1e-9) << v;
    }
    EXPECT_EQ(bounded.inverted, 0);
    EXPECT_LT(LargestDistance(bounded.displacements, unbounded.displacements),
              kSettledToleranceMm);
  }
}

TEST(FemEventBudget, DragInIncrementsWithTheInteractiveBoundCatchesUpAndInvertsNothing) {
  const BarrierDrag d = MakeBarrierDrag();
  ASSERT_FALSE(d.mesh.vertices.empty());
  // The interactive scene's settings (InteractiveFemOptions), the drag in 3
  // events: each of them needs more than the bound.
  const SolverOptions interactive = InteractiveFemOptions().solver;
  ASSERT_GT(interactive.event_newton_budget, 0);
  const DragResult bounded = RunDrag(d, interactive, 3, 40);
  EXPECT_GT(bounded.short_events, 0) << "the drag no longer needs more than its events";
  EXPECT_FALSE(bounded.forced);
  for (int32_t v : bounded.handles) {
    EXPECT_NEAR(glm::distance(bounded.displacements[v], d.drag), 0.0, 1e-9) << v;
  }
  EXPECT_EQ(bounded.inverted, 0);
  // Settled, the state is the unbounded solve's to the interactive
  // tolerances (5% of the last update, PCG to 0.2), which leave it this far
  // from the converged one, mm: 0.04 for the unbounded interactive drag in
  // the same 3 events, 0.01 for this one (docs/FEM.md: ~0.02 mm after the
  // phantom's 12 mm drag).
  const DragResult unbounded = RunDrag(d, Converged(0), 1, 0);
  constexpr double kInteractiveToleranceMm = 0.1;
  EXPECT_LT(LargestDistance(bounded.displacements, unbounded.displacements),
            kInteractiveToleranceMm);
}

// The forced-drag case (forced_drag_test.cc), 30 mm: on the pinned phantom
// mesh the handles at the left renal artery lock against hard vertices
// from about 12 mm on, and the drag is forced bounded or not. Bounded, it
// lags behind the pointer; a forced step must still apply no more than one
// event's share of the motion, as the unbounded drag does (each event forces
// at most its own jump). Forcing the whole lag at once (up to 5.7 mm for
// 3 mm events) inverted 11 tets against 9; one share at a time, 9. (In 20
// events of 1.5 mm, 9 against 8 either way: the forced steps start from
// other states than the unbounded drag's and invert one tet more.)
struct LockedDrag {
  int64_t inverted = -1;
  bool forced = false;
  bool lagged = false;            // some event stopped short of its offset
  double handle_error_mm = -1.0;  // after settling, largest |handle - drag|
};

LockedDrag RunLockedDrag(const FemOptions& options, int events) {
  LockedDrag out;
  const ProxyMesh mesh = testing::PinnedPhantomMesh();
  EXPECT_EQ(mesh.vertices.size(), 250u);
  auto model = FemModel::Create(mesh, testing::BoxExtent(mesh), options);
  EXPECT_TRUE(model.ok()) << model.status();
  if (!model.ok()) return out;
  const auto grab = model->Grab(testing::kPinnedGrabMm, mesh.stats.h_mm);
  EXPECT_TRUE(grab.ok()) << grab.status();
  if (!grab.ok()) return out;
  const glm::dvec3 drag_mm(0.0, 0.0, 30.0);
  const auto check = [&](const Result<SolveStats>& stats) {
    EXPECT_TRUE(stats.ok()) << stats.status();
    if (!stats.ok()) return;
    out.forced |= stats->forced_inversion;
    out.lagged |= stats->target_fraction < 1.0;
  };
  for (int i = 1; i <= events; ++i) {
    check(model->Drag(drag_mm * (static_cast<double>(i) / events)));
  }
  // As many as DeformableScene::Settle's bound for a still frame.
  constexpr int kSettleSolves = 16;
  for (int i = 0; i < kSettleSolves && !model->settled(); ++i) check(model->Settle());
  EXPECT_TRUE(model->settled());
  const auto u = model->Displacements();
  out.handle_error_mm = 0.0;
  for (int32_t h : grab->handles) {
    out.handle_error_mm = std::max(out.handle_error_mm, glm::distance(u[h], drag_mm));
  }
  out.inverted = model->CountInvertedTets();
  return out;
}

TEST(FemEventBudget, LockedDragInEventsForcesNoMoreThanTheUnboundedDrag) {
  constexpr int kEvents = 10;
  const LockedDrag unbounded = RunLockedDrag(FemOptions(), kEvents);
  // The per-event bound of prescribed handles (the interactive default holds
  // handles by springs instead: SpringHandles.LockedDragLagsAndInvertsNothing).
  FemOptions prescribed = InteractiveFemOptions();
  prescribed.attachment = HandleAttachment::kPrescribed;
  const LockedDrag bounded = RunLockedDrag(prescribed, kEvents);
  ASSERT_TRUE(unbounded.forced) << "the drag no longer locks; the case tests nothing";
  EXPECT_TRUE(bounded.lagged) << "the bounded drag no longer lags; the case tests nothing";
  EXPECT_NEAR(bounded.handle_error_mm, 0.0, 1e-9);
  EXPECT_LE(bounded.inverted, unbounded.inverted);
}

TEST(FemEventBudget, ForcedStepLimitIsTheLargestTargetMoveSinceReached) {
  EventBudget budget(12, 4);
  const std::vector<int32_t> constrained = {3, 4, 5};  // vertex 1
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(6);
  // The first Solve after Clear: the move from the state (3-4-5 mm).
  prescribed.segment<3>(3) << 3.0, 4.0, 0.0;
  budget.BeginSolve(prescribed, rest, constrained, rest);
  EXPECT_DOUBLE_EQ(budget.forced_step_limit_mm(), 5.0);
  budget.EndSolve(/*reached=*/false);
  // Lagging: a smaller move keeps the largest since the target was reached,
  // and so does a settle pass (no move).
  prescribed[5] = 1.0;
  budget.BeginSolve(prescribed, rest, constrained, rest);
  EXPECT_DOUBLE_EQ(budget.forced_step_limit_mm(), 5.0);
  budget.EndSolve(false);
  budget.BeginSolve(prescribed, rest, constrained, rest);
  EXPECT_DOUBLE_EQ(budget.forced_step_limit_mm(), 5.0);
  budget.EndSolve(/*reached=*/true);
  // Reached: the next move alone.
  prescribed[5] = 3.0;
  budget.BeginSolve(prescribed, rest, constrained, rest);
  EXPECT_DOUBLE_EQ(budget.forced_step_limit_mm(), 2.0);
  budget.EndSolve(true);
  // New handles: measured from the state again.
  budget.Clear();
  budget.BeginSolve(prescribed, rest, constrained, prescribed);
  EXPECT_DOUBLE_EQ(budget.forced_step_limit_mm(), 0.0);
}

TEST(FemEventBudget, DragLaggingOverTheLimitRunsUnboundedUntilCaughtUp) {
  EventBudget budget(12, 4, /*max_lag_shares=*/2.0);
  const std::vector<int32_t> constrained = {3, 4, 5};  // vertex 1
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd state = Eigen::VectorXd::Zero(6);
  // Events of 1 mm each; the handles reach 0.5 mm of the first.
  prescribed[3] = 1.0;
  budget.BeginSolve(prescribed, none, constrained, state);
  EXPECT_FALSE(budget.unbounded());
  EXPECT_FALSE(budget.RoomForLoadStep(7, 2));
  budget.EndSolve(/*reached=*/false);
  state[3] = 0.5;
  // Behind by 0.5 mm (half a share): still bounded.
  prescribed[3] = 2.0;
  budget.BeginSolve(prescribed, none, constrained, state);
  EXPECT_DOUBLE_EQ(budget.lag_mm(), 0.5);
  EXPECT_FALSE(budget.unbounded());
  budget.EndSolve(false);
  state[3] = 0.8;
  // Behind by 1.2 mm against the last target, then 2.2 mm: over 2 shares.
  prescribed[3] = 3.0;
  budget.BeginSolve(prescribed, none, constrained, state);
  EXPECT_DOUBLE_EQ(budget.lag_mm(), 2.0 - 0.8);
  EXPECT_FALSE(budget.unbounded());
  budget.EndSolve(false);
  prescribed[3] = 4.0;
  budget.BeginSolve(prescribed, none, constrained, state);
  EXPECT_DOUBLE_EQ(budget.lag_mm(), 3.0 - 0.8);
  EXPECT_TRUE(budget.unbounded());
  EXPECT_TRUE(budget.RoomForLoadStep(1000, 2));
  EXPECT_EQ(budget.IterationsFor(1000, 30), 30);
  budget.EndSolve(/*reached=*/true);
  // Caught up: the next event is bounded again.
  state[3] = 4.0;
  prescribed[3] = 5.0;
  budget.BeginSolve(prescribed, none, constrained, state);
  EXPECT_DOUBLE_EQ(budget.lag_mm(), 0.0);
  EXPECT_FALSE(budget.unbounded());
  EXPECT_EQ(budget.IterationsFor(6, 30), 6);
}

TEST(FemEventBudget, NoLagLimitKeepsEveryBoundedSolveBounded) {
  EventBudget budget(12, 4);  // max_lag_shares 0: no limit
  const std::vector<int32_t> constrained = {3, 4, 5};
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(6);
  for (int event = 1; event <= 10; ++event) {
    prescribed[3] = double(event);
    budget.BeginSolve(prescribed, none, constrained, none);  // the handles never move
    EXPECT_FALSE(budget.unbounded()) << "event " << event;
    budget.EndSolve(false);
  }
  EXPECT_DOUBLE_EQ(budget.lag_mm(), 9.0);
}

TEST(FemEventBudget, NegativeOrNanLagLimitIsInvalidArgument) {
  const Volume volume = testing::MakeBodyVolume();
  auto mesh = testing::CentreRefinedMesh(volume);
  ASSERT_TRUE(mesh.ok()) << mesh.status();
  FemOptions options = InteractiveFemOptions();
  EXPECT_DOUBLE_EQ(options.solver.event_max_lag_shares, kInteractiveMaxLagShares);
  for (double bad : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    options.solver.event_max_lag_shares = bad;
    EXPECT_EQ(FemModel::Create(*mesh, volume.geometry().extent_mm(), options).status().code(),
              absl::StatusCode::kInvalidArgument)
        << bad;
  }
}

}  // namespace
}  // namespace vpm

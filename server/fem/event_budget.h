// The per-event work bound of the interactive drag path (docs/FEM.md,
// "Per-event work bound"): a Solve may spend at most a fixed number of
// Newton iterations (tangent solves, each load step's predictor included:
// SolveStats::newton_iterations). When the prescribed jump needs more load
// steps than fit, the Solve stops after the last partial load step: the
// prescribed DOFs stay at the fraction of the jump reached (feasible, in
// equilibrium to the intermediate iterations) and the rest of the motion is
// carried to the next Solve, whose jump (target - current) includes it.
//
// Counts, not milliseconds: a bound in iterations is deterministic (tests can
// check it; the same drag takes the same path on a loaded and an idle
// machine), and each iteration costs one force evaluation and one PCG solve,
// which is where the time of a step goes (drag_loop_bench --steps).
//
// EventBudget also keeps the load steps taken towards a target that a Solve
// left unreached, so that Solves repeated towards the same target (events
// once the pointer stops, or a settle pass) share SolverOptions::
// max_load_steps as one unbounded Solve would, and end exactly at the target
// (at the latest by forced steps) instead of creeping towards it.
//
// A forced step (the barrier finds no feasible fraction, or the load steps
// towards a target ran out) moves the prescribed DOFs without the barrier's
// protection, and the more it moves them at once the more tets it inverts.
// Unbounded, each Solve reaches its target, so a forced step applies at most
// one event's jump. Bounded, the jump of a lagging drag holds the lag too, so
// EventBudget also keeps the forced-step limit: the largest target move of
// the Solves since the target was last reached (one event's share of the
// motion); the rest stays carried, and later Solves force it share by share.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace vpm {

class EventBudget {
 public:
  // newton_iterations: per Solve, 0: unbounded; stop_iterations: of those,
  // kept for bringing the state to equilibrium where a Solve stops short
  // (SolverOptions::event_newton_budget, event_stop_newton_iterations).
  // max_lag_shares: a Solve that starts more than this many event shares
  // (forced_step_limit_mm) behind its last target runs unbounded
  // (SolverOptions::event_max_lag_shares; 0: never).
  explicit EventBudget(int newton_iterations = 0, int stop_iterations = 0,
                       double max_lag_shares = 0.0)
      : newton_iterations_(newton_iterations),
        stop_iterations_(stop_iterations),
        max_lag_shares_(max_lag_shares) {}

  // Starts a Solve towards prescribed_mm (3*#V, read on `constrained`) with
  // external forces force_n (3*#V, N) from displacement_mm (3*#V, the state
  // before the Solve): the load steps carried from earlier Solves are kept
  // when the last Solve left this same load unreached, else dropped.
  void BeginSolve(const Eigen::VectorXd& prescribed_mm, const Eigen::VectorXd& force_n,
                  const std::vector<int32_t>& constrained, const Eigen::VectorXd& displacement_mm);
  // One more load step towards the current load.
  void CountLoadStep() { ++load_steps_; }
  // Load steps towards the current load, earlier Solves' included.
  int load_steps() const { return load_steps_; }
  // Whether a further load step fits in this Solve after `used` Newton
  // iterations: room for a partial one (intermediate iterations) and the
  // stop iterations after it.
  bool RoomForLoadStep(int used, int intermediate) const;
  // Newton iterations a load step that began after `used` may run to: at
  // most `limit`, within the budget.
  int IterationsFor(int used, int limit) const;
  // Ends the Solve: reached (the prescribed DOFs are at the target) drops
  // the carried count; otherwise the load is kept for the next BeginSolve.
  void EndSolve(bool reached);
  // Forgets any carried load and the last target (new handles, reset).
  void Clear();
  // The most a forced step may move a vertex's prescribed DOFs in this Solve,
  // mm: the largest move of the target (largest vertex norm of the change in
  // prescribed_mm on the constrained DOFs) among this Solve and the earlier
  // ones since the target was last reached. The first Solve after Clear (or
  // after the constrained DOFs changed) moves the target from the state.
  double forced_step_limit_mm() const { return forced_step_limit_mm_; }

  int newton_iterations() const { return newton_iterations_; }
  // How far the state's prescribed DOFs were from the last Solve's target
  // when this Solve began (largest vertex norm, mm; 0 when that target was
  // reached or is not comparable).
  double lag_mm() const { return lag_mm_; }
  // Whether this Solve runs without the Newton budget: none is set, or the
  // lag is over max_lag_shares event shares.
  bool unbounded() const { return newton_iterations_ == 0 || catching_up_; }

 private:
  int newton_iterations_ = 0;
  int stop_iterations_ = 0;
  double max_lag_shares_ = 0.0;
  double lag_mm_ = 0.0;
  bool catching_up_ = false;
  int load_steps_ = 0;
  // The unreached load: prescribed values on the constrained DOFs (in the
  // order given), the external forces. Empty when none is carried.
  Eigen::VectorXd carried_prescribed_;
  Eigen::VectorXd carried_force_;
  bool carrying_ = false;
  // The last Solve's target (prescribed_mm, 3*#V, mm) and constrained DOFs,
  // kept after it is reached: the next target's move is measured from it.
  Eigen::VectorXd last_prescribed_;
  std::vector<int32_t> last_constrained_;
  double forced_step_limit_mm_ = 0.0;
};

}  // namespace vpm

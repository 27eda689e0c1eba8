// Quasi-static corotational FEM on a tet mesh with Dirichlet constraints
// (docs/ALGORITHM.md section 5); units in fem_units.h.
//
// Each Solve finds u with f_int(u) = f_ext on the unconstrained DOFs and u =
// the prescribed values on the constrained ones, by Newton-like iterations
// on the corotated tangent (corotated_forces.h; by default R K0 R^T plus the
// clamped rotation-derivative term, i.e. projected Newton; rotations
// refreshed between iterations), each solved inexactly by PCG. The
// preconditioner is the rest stiffness (R = I), factored once at Create with
// SimplicialLDLT; extra prescribed DOFs (handles) reuse its symbolic
// analysis in a numeric refactorization per grab (or, optionally, the factor
// itself through a capacitance correction: ConstrainedFactor), so nothing is
// refactored per step. Solves warm-start from the previous displacement; when
// the previous solve had the same handles and mode, the first iteration uses
// its tangent and residual linearised to the new load instead of a fresh
// force evaluation.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <glm/glm.hpp>

#include "server/common/status.h"
#include "server/fem/constrained_factor.h"
#include "server/fem/corotated_forces.h"
#include "server/fem/event_budget.h"
#include "server/fem/tet_element.h"

namespace vpm {

struct SolverOptions {
  FemMethod method = FemMethod::kCorotationalConsistent;
  // With kCorotationalConsistent: each solve starts with the cheaper
  // R K0 R^T tangent and adds the twist term from Newton iteration
  // adaptive_twist_after + 1 on (mild steps converge before; stressed ones
  // need it). 0: the twist term throughout.
  int adaptive_twist_after = 3;
  int max_newton_iterations = 30;  // per load step
  // Converged when the last Newton update moved no vertex by more than
  // update_tolerance * (largest vertex motion of this solve), dimensionless.
  // The default suits interaction: the next step starts from this state and
  // goes on converging (fem_bench: after a 12 mm drag in 10 steps the
  // displacement is within ~0.005 mm of the converged one); tests and
  // reference solutions use 1e-8 or less.
  double update_tolerance = 5e-2;
  // Relative residual each inner PCG solve stops at (inexact Newton).
  double cg_tolerance = 2e-1;
  int max_cg_iterations = 1000;
  // Threads for the element loops (forces, K v) of meshes of at least
  // kMinTetsToSplit tets; the factor solves stay on one thread. 1 by
  // default: on a shared 2-core machine a second thread mostly waits.
  int threads = 1;
  // Add the inversion barrier (inversion_barrier.h) to the corotated energy
  // and never step across it: no element inverts. Off: the plain model of
  // docs/ALGORITHM.md section 5, which crushes elements in front of a point-like
  // handle dragged further than their size.
  bool inversion_barrier = true;
  // With the barrier: at most this many load steps per Solve (a prescribed
  // jump that would crush an element is applied in feasible parts; after
  // these, or when no part is feasible, the rest at once). The default
  // bounds the cost of an interactive drag step whose handles crush tets
  // whatever the free vertices do (docs/FEM.md, "Cost of the barrier"); 4
  // left inverted tets after 1.5 h drags of point-footprint meshes, 16 with
  // 2 iterations between steps none on the Delaunay meshes but 13 on the
  // flipped, boundary-vertex MRI cell mesh, 32 none
  // (bench/mesh_validity_bench.cc). Measurements (MeasurementFemOptions)
  // allow 64.
  int max_load_steps = 32;
  // A load step shorter than this fraction of the rest of the jump means the
  // prescribed motion itself is crushing an element: the rest is applied at
  // once (SolveStats::forced_inversion). In (0, 1]. Where a bounded drag
  // lags, both the fraction and the forced step are of one event's share of
  // the jump (EventBudget::forced_step_limit_mm), not of the whole lag.
  double min_load_fraction = 1.0 / 64.0;
  // Newton iterations after a partial load step (one that is not the last):
  // the next step's predictor starts from its linearised residual, so the
  // path only has to stay near equilibrium; the last load step iterates up
  // to max_newton_iterations.
  // One left the path so far from equilibrium that the next predictor could
  // only take slivers of the jump (forced inversions); 2 keeps it feasible.
  int intermediate_newton_iterations = 2;
  // How the preconditioner takes the grab's handles (constrained_factor.h):
  // a numeric refactorization per grab on the symbolic analysis made once
  // (one plain solve per PCG iteration), or the factor without them plus a
  // capacitance correction (a dense #free by #handle-DOF product per
  // iteration). drag_loop_bench --handle-factor measures both.
  HandleFactor handle_factor = HandleFactor::kRefactor;
  // Per-event work bound (event_budget.h): at most this many Newton
  // iterations (SolveStats::newton_iterations) per Solve; a jump that needs
  // more load steps stops at the fraction reached and the rest is carried to
  // the next Solve (SolveStats::target_fraction). 0: unbounded, every Solve
  // reaches its target (a single Solve's default; the interactive scene sets
  // kInteractiveEventNewtonBudget). Else at least
  // intermediate_newton_iterations + event_stop_newton_iterations.
  int event_newton_budget = 0;
  // Of event_newton_budget, the Newton iterations kept for equilibrium at
  // the fraction reached when a Solve stops short: without them the next
  // event starts from the last partial step's (intermediate) state, and
  // the feasible load steps shrink event after event until the rest is
  // forced (drag_loop_bench, docs/FEM.md "Per-event work bound").
  int event_stop_newton_iterations = 4;
  // The most a bounded drag may lag, in event shares (EventBudget::
  // forced_step_limit_mm, the largest target move since the target was
  // last reached): a Solve that starts further behind its last target than
  // this many shares runs unbounded and catches up, as an unbounded Solve
  // would. Where the handles lock against hard vertices, each bounded event
  // reaches a few percent of its jump and the lag grew to 4.5 mm on the
  // 6,426-vertex mesh, which the settle then forced in shares: 73 inverted
  // tets against 17 unbounded (docs/FEM.md, "Per-event work bound"). 0: no
  // limit (the interactive scene sets kInteractiveMaxLagShares). Only with
  // event_newton_budget.
  double event_max_lag_shares = 0.0;
};

// The interactive scene's per-event bound (InteractiveFemOptions): at most 4
// partial load steps and 4 iterations where a step stops short. In
// drag_loop_bench at 1,318 vertices the unbounded worst step took 24 Newton
// iterations (12 load steps), 3.9x the mean FEM step; with 12 the worst is
// 2.0-2.3x, and 8 (tried, 2 kept) settled the lag in twice the iterations
// (docs/FEM.md, "Per-event work bound").
inline constexpr int kInteractiveEventNewtonBudget = 12;
// The interactive scene's lag limit (SolverOptions::event_max_lag_shares).
inline constexpr double kInteractiveMaxLagShares = 2.0;

// Below this many tets the element loops run on one thread (a split costs
// thread start-ups of ~20-50 us against loops of < 1 ms).
inline constexpr int64_t kMinTetsToSplit = 4000;

// Handles: prescribed displacement (drag), free with forces (pull), or held
// by springs towards their targets (SetHandleSprings: the interactive drag,
// whose barrier always wins against the springs, so no element inverts).
enum class HandleMode { kPrescribed, kFree, kSpring };

struct SolveStats {
  double assembly_ms = 0.0;  // rotations and elastic forces, all evaluations
  double solve_ms = 0.0;     // PCG (preconditioner and matrix-free products)
  double precondition_ms = 0.0;  // the factor solves inside solve_ms
  int newton_iterations = 0;
  int cg_iterations = 0;  // summed over Newton iterations
  int load_steps = 0;     // parts the prescribed jump was applied in
  // Newton updates shortened to keep every element's volume ratio positive.
  int shortened_updates = 0;
  // The prescribed motion could not be reached without flattening an
  // element, and was applied regardless (it may leave inverted elements);
  // at most one event's share of it where a bounded drag lags (the rest
  // carried: target_fraction < 1).
  bool forced_inversion = false;
  // |f_ext - f_int| on the free DOFs / (|f_int| + |f_ext|) over all DOFs,
  // dimensionless, at the state the last Newton update started from (the
  // solve stops after an update without evaluating again; that update
  // reduces it further).
  double residual = 0.0;
  double max_displacement_mm = 0.0;  // largest vertex displacement
  // Of the prescribed motion asked for (target - start on the prescribed
  // DOFs; every DOF moves by the same fraction), the part reached, in
  // [0, 1]; below 1 only with SolverOptions::event_newton_budget, the rest
  // (largest vertex distance still to go: remaining_mm, mm) carried to the
  // next Solve.
  double target_fraction = 1.0;
  double remaining_mm = 0.0;
  // Converged at the target: false too when the target is not reached.
  bool converged = false;
  // kSpring: the largest distance of a spring-held DOF's vertex from its
  // target at the end (mm): how far the held tissue lags its pointer.
  double spring_lag_mm = 0.0;
  double total_ms() const { return assembly_ms + solve_ms; }
};

// InvalidArgument naming the first setting out of range (iteration limits,
// tolerances, the per-event bound); what CorotationalSolver::Create checks,
// for callers that want to refuse bad settings before building a mesh.
Status CheckSolverOptions(const SolverOptions& options);

class CorotationalSolver {
 public:
  // Builds elements, assembles the rest stiffness and factors its free block.
  //   rest_mm          #V by 3, mm
  //   tets             #T by 4 indices, positive orientation
  //   young_n_per_mm2  #T Young's moduli, N/mm^2
  //   poisson          in (-1, 0.5)
  //   fixed_dofs       3*#V flags, 1 = always prescribed (vertex v axis i at 3v+i)
  // Fails: InvalidArgument for bad inputs, FailedPrecondition when the
  // constraints leave a rigid motion free.
  static Result<CorotationalSolver> Create(const std::vector<glm::dvec3>& rest_mm,
                                           const std::vector<std::array<int32_t, 4>>& tets,
                                           const std::vector<double>& young_n_per_mm2,
                                           double poisson, const std::vector<uint8_t>& fixed_dofs,
                                           const SolverOptions& options = {});

  // An empty solver (no vertices); use Create.
  CorotationalSolver() = default;

  // Sets the handle DOFs (each not in fixed_dofs, no repeats; empty: none).
  // Costs one factor solve per DOF. InvalidArgument on a bad DOF.
  Status SetHandles(const std::vector<int32_t>& handle_dofs);
  // Sets the handle DOFs as spring-held for kSpring solves: DOF handle_dofs[j]
  // is pulled towards its target by stiffness_n_per_mm[j] (> 0, N/mm). One
  // numeric refactorization (kRefactor). InvalidArgument on bad input.
  Status SetHandleSprings(const std::vector<int32_t>& handle_dofs,
                          const std::vector<double>& stiffness_n_per_mm);
  // The diagonal of the rest stiffness (3*#V, N/mm), e.g. to scale springs.
  const Eigen::VectorXd& rest_diagonal() const { return rest_diagonal_; }

  // Solves for equilibrium, warm-started from the current displacement.
  //   prescribed_mm  3*#V; read on fixed DOFs and, in kPrescribed mode, on
  //                  handle DOFs, mm
  //   force_n        3*#V external nodal forces, read on the free DOFs, N
  // kSpring (after SetHandleSprings): prescribed_mm on the handle DOFs are
  // the springs' targets; Newton from the current state, each update cut to
  // stay feasible (the barrier), at most event_newton_budget iterations
  // when that is set; no load steps, nothing forced.
  // Not converging within the iteration limits is not an error (see
  // stats.converged); non-finite inputs are InvalidArgument, a non-finite
  // state is Internal and restores the previous displacement.
  Result<SolveStats> Solve(const Eigen::VectorXd& prescribed_mm, const Eigen::VectorXd& force_n,
                           HandleMode mode);

  // Back to rest: every displacement exactly 0.
  void Reset();

  int64_t vertex_count() const { return static_cast<int64_t>(displacement_.size() / 3); }
  const Eigen::VectorXd& displacement_mm() const { return displacement_; }  // 3*#V, mm
  const std::vector<TetElement>& elements() const { return elements_; }
  // Element rotations (#T) and twist terms at the last evaluated state.
  const CorotatedFrames& frames() const { return frames_; }
  const std::vector<uint8_t>& fixed_dofs() const { return fixed_; }
  const std::vector<int32_t>& handle_dofs() const { return handles_; }
  const SolverOptions& options() const { return options_; }
  double setup_assembly_ms() const { return setup_assembly_ms_; }  // elements + rest K
  double setup_factor_ms() const { return setup_factor_ms_; }
  const ConstrainedFactor& factor() const { return factor_; }

 private:
  Status CheckLoad(const Eigen::VectorXd& prescribed_mm, const Eigen::VectorXd& force_n) const;
  Result<SolveStats> SolveSprings(const Eigen::VectorXd& target_mm, const Eigen::VectorXd& force_n);
  // Largest vertex distance of the spring DOFs from target_mm, mm.
  double SpringLag(const Eigen::VectorXd& target_mm) const;
  // Rotations and forces at displacement_; returns the residual on the free
  // DOFs into residual_ and its relative size.
  double Evaluate(const Eigen::VectorXd& force_n, const std::vector<int32_t>& constrained,
                  FemMethod method);
  double MaxVertexNorm(const Eigen::VectorXd& v) const;
  int ElementThreads() const;
  // PCG on K(frames_) du = rhs (constrained DOFs 0); keeps the PCG residual
  // in linear_residual_ and counts one Newton iteration. Returns du, mm.
  Eigen::VectorXd TangentSolve(const Eigen::VectorXd& rhs, const std::vector<int32_t>& constrained,
                               bool with_handles, SolveStats& stats);
  // One Newton iteration: TangentSolve, then displacement_ += du (with the
  // barrier: alpha du, the largest feasible alpha <= 1). Returns max vertex
  // |du|, mm (infinity for a shortened update).
  double NewtonUpdate(const Eigen::VectorXd& rhs, const std::vector<int32_t>& constrained,
                      bool with_handles, SolveStats& stats);
  // Newton iterations from displacement_ until the update tolerance,
  // max_iterations (counted from stats.newton_iterations = first_iteration)
  // or round-off; step_scale (mm) is this load step's motion. Internal (state
  // restored to start) when the state becomes non-finite.
  Status Equilibrate(const Eigen::VectorXd& force_n, const std::vector<int32_t>& constrained,
                     bool with_handles, const Eigen::VectorXd& start, double step_scale,
                     int first_iteration, int max_iterations, SolveStats& stats);
  // Elements whose every DOF is in `constrained`: their shape is the
  // load's, and no step size can change it, so the barrier does not limit
  // the steps (one flag per element).
  std::vector<uint8_t> PrescribedElements(const std::vector<int32_t>& constrained) const;
  // One load step's move of displacement_ towards the prescribed `jump`:
  // the predictor's direction times the largest feasible fraction (alpha),
  // or, where no fraction is feasible, a forced fraction of the jump on the
  // prescribed DOFs alone; without the barrier and a warm tangent, the jump.
  struct LoadStepMove {
    double alpha = 1.0;
    double forced_fraction = 1.0;  // of the jump, when the step is forced
  };
  LoadStepMove MoveLoadStep(const Eigen::VectorXd& jump, const Eigen::VectorXd& force_n,
                            const std::vector<int32_t>& constrained, bool with_handles,
                            HandleMode mode, const std::vector<uint8_t>& prescribed_elements,
                            SolveStats& stats);
  // A solve's end: the tangent kept for the next one, the budget told
  // whether the target was reached, and the stats' fraction reached.
  SolveStats FinishSolve(SolveStats stats, bool carried, double first_jump_mm,
                         const Eigen::VectorXd& force_n, HandleMode mode);

  SolverOptions options_;
  std::vector<TetElement> elements_;
  std::vector<uint8_t> fixed_;
  std::vector<int32_t> fixed_list_;
  std::vector<int32_t> handles_;
  std::vector<double> spring_k_;  // per handle DOF, N/mm; empty: prescribed handles
  // During a kSpring solve: the springs' targets (3*#V, mm), else null.
  const Eigen::VectorXd* spring_target_ = nullptr;
  Eigen::VectorXd rest_diagonal_;
  ConstrainedFactor factor_;
  EventBudget budget_;
  Eigen::VectorXd displacement_;
  CorotatedFrames frames_;
  Eigen::VectorXd forces_;    // elastic forces at the last evaluation
  Eigen::VectorXd residual_;  // f_ext - f_int, 0 on constrained DOFs
  // The residual at displacement_ linearised from the last evaluation (valid
  // when linearized_), with the mode and external force it was built for.
  Eigen::VectorXd linear_residual_;
  bool linearized_ = false;
  HandleMode linearized_mode_ = HandleMode::kPrescribed;
  Eigen::VectorXd linearized_force_;
  double setup_assembly_ms_ = 0.0;
  double setup_factor_ms_ = 0.0;
};

}  // namespace vpm

#include "server/fem/corotational_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "server/common/clock.h"
#include "server/fem/assemble_stiffness.h"
#include "server/fem/inversion_barrier.h"
#include "server/fem/projected_pcg.h"

namespace vpm {
namespace {

// Below this relative residual the state is in equilibrium to round-off.
constexpr double kRoundOffResidual = 1e-13;

// With the barrier: an update may take at most 1 - kFeasibleKeep of an
// element's volume ratio below the onset (FeasibleStepFraction).
constexpr double kFeasibleKeep = 0.2;

// The fraction of a jump of jump_mm (largest vertex norm) that a forced
// step applies when it may move a vertex at most limit_mm: all of it unless
// that exceeds the limit by more than round-off (an unbounded drag's jump is
// its target's move up to round-off).
double ForcedFraction(double jump_mm, double limit_mm) {
  return jump_mm > limit_mm * (1.0 + 1e-9) && limit_mm > 0.0 ? limit_mm / jump_mm : 1.0;
}

}  // namespace

Status CheckSolverOptions(const SolverOptions& options) {
  if (options.max_newton_iterations < 1 || options.max_cg_iterations < 1 || options.threads < 1 ||
      options.adaptive_twist_after < 0 || options.max_load_steps < 1 ||
      options.intermediate_newton_iterations < 1 ||
      !(options.min_load_fraction > 0.0 && options.min_load_fraction <= 1.0) ||
      !(options.update_tolerance > 0.0) || !(options.cg_tolerance > 0.0)) {
    return absl::InvalidArgumentError("solver iteration limits and tolerances must be > 0");
  }
  if (options.event_stop_newton_iterations < 0 ||
      (options.event_newton_budget != 0 &&
       options.event_newton_budget <
           options.intermediate_newton_iterations + options.event_stop_newton_iterations)) {
    return absl::InvalidArgumentError(
        StrCat("event_newton_budget (", options.event_newton_budget,
               ") must be 0 (unbounded) or at least intermediate_newton_iterations (",
               options.intermediate_newton_iterations, ") + event_stop_newton_iterations (",
               options.event_stop_newton_iterations, ")"));
  }
  if (!(options.event_max_lag_shares >= 0.0) || !std::isfinite(options.event_max_lag_shares)) {
    return absl::InvalidArgumentError(StrCat("event_max_lag_shares (",
                                             options.event_max_lag_shares,
                                             ") must be finite and >= 0 (0: no limit)"));
  }
  return absl::OkStatus();
}

Result<CorotationalSolver> CorotationalSolver::Create(
    const std::vector<glm::dvec3>& rest_mm, const std::vector<std::array<int32_t, 4>>& tets,
    const std::vector<double>& young_n_per_mm2, double poisson,
    const std::vector<uint8_t>& fixed_dofs, const SolverOptions& options) {
  if (fixed_dofs.size() != 3 * rest_mm.size()) {
    return absl::InvalidArgumentError(StrCat("got ", fixed_dofs.size(), " DOF flags for ",
                                             rest_mm.size(), " vertices (need 3 per vertex)"));
  }
  if (!(poisson > -1.0 && poisson < 0.5)) {
    return absl::InvalidArgumentError(StrCat("poisson must lie in (-1, 0.5), got ", poisson));
  }
  RETURN_IF_ERROR(CheckSolverOptions(options));
  CorotationalSolver solver;
  solver.options_ = options;
  solver.budget_ = EventBudget(options.event_newton_budget, options.event_stop_newton_iterations,
                               options.event_max_lag_shares);
  const auto t0 = SteadyClock::now();
  ASSIGN_OR_RETURN(solver.elements_, MakeTetElements(rest_mm, tets, young_n_per_mm2, poisson));
  const Eigen::SparseMatrix<double> rest_stiffness =
      AssembleStiffness(solver.elements_, CorotatedFrames{}, static_cast<int64_t>(rest_mm.size()));
  solver.setup_assembly_ms_ = MsSince(t0);
  solver.rest_diagonal_ = rest_stiffness.diagonal();
  const auto t1 = SteadyClock::now();
  ASSIGN_OR_RETURN(solver.factor_, ConstrainedFactor::Create(rest_stiffness, fixed_dofs,
                                                                options.handle_factor));
  solver.setup_factor_ms_ = MsSince(t1);
  solver.fixed_ = fixed_dofs;
  for (size_t d = 0; d < fixed_dofs.size(); ++d) {
    if (fixed_dofs[d]) solver.fixed_list_.push_back(static_cast<int32_t>(d));
  }
  solver.displacement_.setZero(3 * static_cast<int64_t>(rest_mm.size()));
  solver.Reset();
  return solver;
}

Status CorotationalSolver::SetHandles(const std::vector<int32_t>& handle_dofs) {
  RETURN_IF_ERROR(factor_.SetExtraFixed(handle_dofs));
  handles_ = handle_dofs;
  spring_k_.clear();
  linearized_ = false;
  budget_.Clear();
  return absl::OkStatus();
}

Status CorotationalSolver::SetHandleSprings(const std::vector<int32_t>& handle_dofs,
                                            const std::vector<double>& stiffness_n_per_mm) {
  RETURN_IF_ERROR(factor_.SetSprings(handle_dofs, stiffness_n_per_mm));
  handles_ = handle_dofs;
  spring_k_ = stiffness_n_per_mm;
  linearized_ = false;
  budget_.Clear();
  return absl::OkStatus();
}

void CorotationalSolver::Reset() {
  displacement_.setZero();
  frames_.rotations.assign(elements_.size(), Eigen::Matrix3d::Identity());
  frames_.twist.clear();
  frames_.twisted.clear();
  frames_.barrier.clear();
  linearized_ = false;
  budget_.Clear();
}

Status CorotationalSolver::CheckLoad(const Eigen::VectorXd& prescribed_mm,
                                     const Eigen::VectorXd& force_n) const {
  if (prescribed_mm.size() != displacement_.size() || force_n.size() != displacement_.size()) {
    return absl::InvalidArgumentError(
        StrCat("prescribed (", prescribed_mm.size(), ") and force (", force_n.size(),
               ") vectors must have 3*#V = ", displacement_.size(), " entries"));
  }
  if (!prescribed_mm.allFinite() || !force_n.allFinite()) {
    return absl::InvalidArgumentError("prescribed displacements and forces must be finite");
  }
  return absl::OkStatus();
}

double CorotationalSolver::MaxVertexNorm(const Eigen::VectorXd& v) const {
  double largest = 0.0;
  for (int64_t i = 0; i < v.size(); i += 3) largest = std::max(largest, v.segment<3>(i).norm());
  return largest;
}

int CorotationalSolver::ElementThreads() const {
  return static_cast<int64_t>(elements_.size()) >= kMinTetsToSplit ? options_.threads : 1;
}

double CorotationalSolver::Evaluate(const Eigen::VectorXd& force_n,
                                    const std::vector<int32_t>& constrained, FemMethod method) {
  CorotatedForces(elements_, displacement_, method, frames_, forces_, ElementThreads(),
                  options_.inversion_barrier);
  Eigen::VectorXd applied = force_n;
  if (spring_target_ != nullptr) {
    for (size_t j = 0; j < handles_.size(); ++j) {
      const int32_t d = handles_[j];
      applied[d] += spring_k_[j] * ((*spring_target_)[d] - displacement_[d]);
    }
  }
  residual_ = applied - forces_;
  for (int32_t d : constrained) {
    residual_[d] = 0.0;
    applied[d] = 0.0;
  }
  const double reference = forces_.norm() + applied.norm();
  const double r = residual_.norm();
  if (!std::isfinite(r) || !std::isfinite(reference))
    return std::numeric_limits<double>::quiet_NaN();
  return reference > 0.0 ? r / reference : 0.0;
}

Eigen::VectorXd CorotationalSolver::TangentSolve(const Eigen::VectorXd& rhs,
                                                 const std::vector<int32_t>& constrained,
                                                 bool with_handles, SolveStats& stats) {
  const auto t0 = SteadyClock::now();
  const LinearMap apply_k = [this](const Eigen::VectorXd& v, Eigen::VectorXd& y) {
    ApplyCorotatedStiffness(elements_, frames_, v, y, ElementThreads());
    if (spring_target_ != nullptr) {
      for (size_t j = 0; j < handles_.size(); ++j) y[handles_[j]] += spring_k_[j] * v[handles_[j]];
    }
  };
  const LinearMap precondition = [this, with_handles, &stats](const Eigen::VectorXd& r,
                                                              Eigen::VectorXd& z) {
    const auto t_factor = SteadyClock::now();
    factor_.Apply(r, with_handles, z);
    stats.precondition_ms += MsSince(t_factor);
  };
  Eigen::VectorXd update;
  const PcgStats pcg = ProjectedPcg(apply_k, precondition, constrained, rhs, options_.cg_tolerance,
                                    options_.max_cg_iterations, update, &linear_residual_);
  stats.solve_ms += MsSince(t0);
  ++stats.newton_iterations;
  stats.cg_iterations += pcg.iterations;
  return update;
}

double CorotationalSolver::NewtonUpdate(const Eigen::VectorXd& rhs,
                                        const std::vector<int32_t>& constrained, bool with_handles,
                                        SolveStats& stats) {
  const Eigen::VectorXd update = TangentSolve(rhs, constrained, with_handles, stats);
  const double alpha = options_.inversion_barrier
                           ? FeasibleStepFraction(elements_, displacement_, update, kFeasibleKeep)
                           : 1.0;
  if (alpha < 1.0) {
    // The residual linearised at the shortened step: rhs - alpha K du.
    linear_residual_ = (1.0 - alpha) * rhs + alpha * linear_residual_;
    ++stats.shortened_updates;
  }
  displacement_ += alpha * update;
  // A shortened update says nothing about convergence.
  return alpha == 1.0 ? MaxVertexNorm(update) : std::numeric_limits<double>::infinity();
}

Status CorotationalSolver::Equilibrate(const Eigen::VectorXd& force_n,
                                       const std::vector<int32_t>& constrained, bool with_handles,
                                       const Eigen::VectorXd& start, double step_scale,
                                       int first_iteration, int max_iterations,
                                       SolveStats& stats) {
  stats.converged = false;
  for (;;) {
    const auto t0 = SteadyClock::now();
    const int iterations = stats.newton_iterations - first_iteration;
    const bool plain_first = options_.method == FemMethod::kCorotationalConsistent &&
                             iterations < options_.adaptive_twist_after;
    stats.residual =
        Evaluate(force_n, constrained, plain_first ? FemMethod::kCorotational : options_.method);
    stats.assembly_ms += MsSince(t0);
    if (!std::isfinite(stats.residual)) {
      displacement_ = start;
      return absl::InternalError("the FEM state became non-finite; displacement restored");
    }
    linear_residual_ = residual_;
    if (stats.residual <= kRoundOffResidual) {
      stats.converged = true;
      return absl::OkStatus();
    }
    if (iterations >= max_iterations) return absl::OkStatus();
    const double moved = NewtonUpdate(residual_, constrained, with_handles, stats);
    step_scale = std::max(step_scale, MaxVertexNorm(displacement_ - start));
    // Stopping here, without evaluating the new state, saves one force
    // evaluation per step; the residual reported is the one before the update.
    if (moved <= options_.update_tolerance * step_scale) {
      stats.converged = true;
      return absl::OkStatus();
    }
  }
}

std::vector<uint8_t> CorotationalSolver::PrescribedElements(
    const std::vector<int32_t>& constrained) const {
  std::vector<uint8_t> is_constrained(displacement_.size(), 0);
  for (int32_t d : constrained) is_constrained[d] = 1;
  std::vector<uint8_t> prescribed(elements_.size(), 1);
  for (size_t t = 0; t < elements_.size(); ++t) {
    for (int32_t v : elements_[t].vertices) {
      for (int i = 0; i < 3; ++i) prescribed[t] &= is_constrained[3 * v + i];
    }
  }
  return prescribed;
}

CorotationalSolver::LoadStepMove CorotationalSolver::MoveLoadStep(
    const Eigen::VectorXd& jump, const Eigen::VectorXd& force_n,
    const std::vector<int32_t>& constrained, bool with_handles, HandleMode mode,
    const std::vector<uint8_t>& prescribed_elements, SolveStats& stats) {
  LoadStepMove move;
  const bool warm = linearized_ && linearized_mode_ == mode;
  if (!warm && !options_.inversion_barrier) {
    displacement_ += jump;
    return move;
  }
  // Predictor, without evaluating forces: the prescribed DOFs take the
  // jump and the free ones follow through the last tangent, with the
  // residual linearised from the last solve when there is one:
  // K du = r_last + df_ext - K jump.
  const auto t0 = SteadyClock::now();
  Eigen::VectorXd rhs = warm ? Eigen::VectorXd(linear_residual_ + (force_n - linearized_force_))
                             : Eigen::VectorXd::Zero(jump.size());
  Eigen::VectorXd k_jump;
  ApplyCorotatedStiffness(elements_, frames_, jump, k_jump, ElementThreads());
  rhs -= k_jump;
  for (int32_t d : constrained) rhs[d] = 0.0;
  stats.assembly_ms += MsSince(t0);
  const Eigen::VectorXd direction = jump + TangentSolve(rhs, constrained, with_handles, stats);
  if (options_.inversion_barrier) {
    // The least fraction worth a load step is of one event's share: of
    // a lagging drag's longer jump it would give up sooner than an
    // unbounded drag does.
    const double min_fraction = options_.min_load_fraction *
                                ForcedFraction(stats.remaining_mm, budget_.forced_step_limit_mm());
    move.alpha = budget_.load_steps() <= options_.max_load_steps
                     ? FeasibleStepFraction(elements_, displacement_, direction, kFeasibleKeep,
                                            min_fraction, prescribed_elements)
                     : 0.0;
    if (move.alpha == 0.0) {
      // No feasible part (or no load steps left): the prescribed motion
      // itself flattens an element, e.g. a handle edge sweeping over a
      // fixed vertex, where nothing free can make room. The rest is
      // applied at once; elements it inverts lose their barrier
      // (inversion_barrier.h) and the caller counts them.
      stats.forced_inversion = true;
      move.alpha = 1.0;
      move.forced_fraction = ForcedFraction(stats.remaining_mm, budget_.forced_step_limit_mm());
    }
  }
  // A forced step moves only the prescribed DOFs: the free ones stay at
  // the last equilibrium. The predictor's free part is the tangent's
  // extrapolation of a jump it has just found infeasible, through
  // barrier terms that grow without bound near J = 0; taken whole it
  // threw free vertices over 100 mm for a 20 mm drag (a vertex 115 mm,
  // 81 tets inverted) and Newton never came back from there
  // (CorotationalSolver.ForcedDragMovesNothingFurtherThanTheHandles).
  // A lagging drag's jump holds the lag too; a forced step applies at
  // most one event's share of it (EventBudget::forced_step_limit_mm), as
  // an unbounded drag would, and the rest stays carried: forcing a 5.7 mm
  // lag at once inverted more tets than the unbounded drag's 3 mm steps
  // (FemEventBudget.LockedDragInEventsForcesNoMoreThanTheUnboundedDrag).
  displacement_ += stats.forced_inversion ? Eigen::VectorXd(move.forced_fraction * jump)
                                          : Eigen::VectorXd(move.alpha * direction);
  return move;
}

SolveStats CorotationalSolver::FinishSolve(SolveStats stats, bool carried, double first_jump_mm,
                                           const Eigen::VectorXd& force_n, HandleMode mode) {
  linearized_ = true;
  linearized_mode_ = mode;
  linearized_force_ = force_n;
  budget_.EndSolve(!carried);
  if (carried) {
    stats.converged = false;
    stats.target_fraction = first_jump_mm > 0.0 ? 1.0 - stats.remaining_mm / first_jump_mm : 1.0;
  } else {
    stats.remaining_mm = 0.0;
  }
  stats.max_displacement_mm = MaxVertexNorm(displacement_);
  return stats;
}

Result<SolveStats> CorotationalSolver::Solve(const Eigen::VectorXd& prescribed_mm,
                                             const Eigen::VectorXd& force_n, HandleMode mode) {
  RETURN_IF_ERROR(CheckLoad(prescribed_mm, force_n));
  if (mode == HandleMode::kSpring) return SolveSprings(prescribed_mm, force_n);
  const bool with_handles = mode == HandleMode::kPrescribed;
  std::vector<int32_t> constrained = fixed_list_;
  if (with_handles) constrained.insert(constrained.end(), handles_.begin(), handles_.end());
  const Eigen::VectorXd start = displacement_;
  SolveStats stats;
  budget_.BeginSolve(prescribed_mm, force_n, constrained, displacement_);
  double first_jump_mm = -1.0;  // the prescribed motion asked for
  bool carried = false;         // the budget stopped short of the target
  const std::vector<uint8_t> prescribed_elements =
      options_.inversion_barrier ? PrescribedElements(constrained) : std::vector<uint8_t>{};
  // The prescribed DOFs move in load steps: all at once unless that would
  // crush an element (inversion barrier), then by the largest feasible
  // fraction of what is left, each step brought to equilibrium.
  for (;;) {
    Eigen::VectorXd jump = Eigen::VectorXd::Zero(displacement_.size());
    for (int32_t d : constrained) jump[d] = prescribed_mm[d] - displacement_[d];
    stats.remaining_mm = MaxVertexNorm(jump);
    if (first_jump_mm < 0.0) first_jump_mm = stats.remaining_mm;
    // Per-event bound: after a partial load step, the rest of the jump waits
    // for the next Solve unless a further partial step fits; the iterations
    // left bring the state at the fraction reached towards equilibrium.
    if (stats.load_steps > 0 && !budget_.RoomForLoadStep(stats.newton_iterations,
                                                         options_.intermediate_newton_iterations)) {
      carried = true;
      const int used = stats.newton_iterations;
      RETURN_IF_ERROR(Equilibrate(
          force_n, constrained, with_handles, start, MaxVertexNorm(displacement_ - start), used,
          budget_.IterationsFor(used, options_.max_newton_iterations), stats));
      break;
    }
    const Eigen::VectorXd step_start = displacement_;
    const int first_iteration = stats.newton_iterations;
    ++stats.load_steps;
    budget_.CountLoadStep();
    const LoadStepMove move =
        MoveLoadStep(jump, force_n, constrained, with_handles, mode, prescribed_elements, stats);
    linearized_ = false;
    RETURN_IF_ERROR(Equilibrate(
        force_n, constrained, with_handles, start, MaxVertexNorm(displacement_ - step_start),
        first_iteration,
        budget_.IterationsFor(first_iteration, move.alpha == 1.0
                                                   ? options_.max_newton_iterations
                                                   : options_.intermediate_newton_iterations),
        stats));
    if (move.forced_fraction < 1.0) {
      carried = true;
      stats.remaining_mm *= 1.0 - move.forced_fraction;
      break;
    }
    if (move.alpha == 1.0) break;
    // The last update's linearised residual starts the next load step.
    linearized_ = true;
    linearized_mode_ = mode;
    linearized_force_ = force_n;
  }
  return FinishSolve(stats, carried, first_jump_mm, force_n, mode);
}

double CorotationalSolver::SpringLag(const Eigen::VectorXd& target_mm) const {
  double lag = 0.0;
  for (size_t j = 0; j < handles_.size();) {
    const int32_t vertex = handles_[j] / 3;
    double squared = 0.0;
    for (; j < handles_.size() && handles_[j] / 3 == vertex; ++j) {
      const double gap = target_mm[handles_[j]] - displacement_[handles_[j]];
      squared += gap * gap;
    }
    lag = std::max(lag, std::sqrt(squared));
  }
  return lag;
}

Result<SolveStats> CorotationalSolver::SolveSprings(const Eigen::VectorXd& target_mm,
                                                    const Eigen::VectorXd& force_n) {
  if (spring_k_.empty() && !handles_.empty()) {
    return absl::FailedPreconditionError("a spring solve needs SetHandleSprings first");
  }
  const Eigen::VectorXd start = displacement_;
  SolveStats stats;
  stats.load_steps = 1;
  const double asked_mm = SpringLag(target_mm);
  const int iterations = options_.event_newton_budget > 0 ? options_.event_newton_budget
                                                          : options_.max_newton_iterations;
  // Newton on elastic + barrier + spring energy from the current state; each
  // update is cut to stay feasible, so no element crosses J = 0 and the
  // springs stretch instead where the tissue cannot follow.
  linearized_ = false;
  spring_target_ = &target_mm;
  const Status status = Equilibrate(force_n, fixed_list_, /*with_handles=*/true, start, asked_mm,
                                    0, iterations, stats);
  spring_target_ = nullptr;
  if (!status.ok()) return status;
  stats.spring_lag_mm = SpringLag(target_mm);
  stats.max_displacement_mm = MaxVertexNorm(displacement_);
  return stats;
}

}  // namespace vpm

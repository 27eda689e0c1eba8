#include "server/fem/event_budget.h"

#include <algorithm>
#include <cmath>

namespace vpm {
namespace {

Eigen::VectorXd Gather(const Eigen::VectorXd& values, const std::vector<int32_t>& dofs) {
  Eigen::VectorXd out(static_cast<int64_t>(dofs.size()));
  for (size_t i = 0; i < dofs.size(); ++i) out[static_cast<int64_t>(i)] = values[dofs[i]];
  return out;
}

// The largest vertex norm of (a - b) over `dofs` (3*#V vectors), mm.
double LargestVertexMove(const Eigen::VectorXd& a, const Eigen::VectorXd& b,
                         const std::vector<int32_t>& dofs) {
  Eigen::VectorXd squared = Eigen::VectorXd::Zero(a.size() / 3);
  for (int32_t d : dofs) squared[d / 3] += (a[d] - b[d]) * (a[d] - b[d]);
  return squared.size() > 0 ? std::sqrt(squared.maxCoeff()) : 0.0;
}

}  // namespace

void EventBudget::BeginSolve(const Eigen::VectorXd& prescribed_mm, const Eigen::VectorXd& force_n,
                             const std::vector<int32_t>& constrained,
                             const Eigen::VectorXd& displacement_mm) {
  Eigen::VectorXd target = Gather(prescribed_mm, constrained);
  // Exact comparison: a settle pass repeats the same offset, and any new
  // pointer position is a new load.
  const bool same = carrying_ && target.size() == carried_prescribed_.size() &&
                    target == carried_prescribed_ && force_n.size() == carried_force_.size() &&
                    force_n == carried_force_;
  if (!same) load_steps_ = 0;
  // With no earlier target for these DOFs, the move is the jump itself.
  const bool comparable =
      last_constrained_ == constrained && last_prescribed_.size() == prescribed_mm.size();
  // The lag: what the last Solve left of its target.
  lag_mm_ = carrying_ && comparable
                ? LargestVertexMove(last_prescribed_, displacement_mm, constrained)
                : 0.0;
  const double move_mm = LargestVertexMove(
      prescribed_mm, comparable ? last_prescribed_ : displacement_mm, constrained);
  // While a lag is carried, it holds the moves of every Solve since the
  // target was last reached; a forced step may apply the largest of them.
  forced_step_limit_mm_ =
      carrying_ && comparable ? std::max(forced_step_limit_mm_, move_mm) : move_mm;
  catching_up_ = max_lag_shares_ > 0.0 && lag_mm_ > max_lag_shares_ * forced_step_limit_mm_;
  last_prescribed_ = prescribed_mm;
  last_constrained_ = constrained;
  carried_prescribed_ = std::move(target);
  carried_force_ = force_n;
  carrying_ = true;
}

bool EventBudget::RoomForLoadStep(int used, int intermediate) const {
  return unbounded() || used + intermediate + stop_iterations_ <= newton_iterations_;
}

int EventBudget::IterationsFor(int used, int limit) const {
  return unbounded() ? limit : std::min(limit, newton_iterations_ - used);
}

void EventBudget::EndSolve(bool reached) {
  if (!reached) return;
  load_steps_ = 0;
  carrying_ = false;
  carried_prescribed_.resize(0);
  carried_force_.resize(0);
}

void EventBudget::Clear() {
  EndSolve(/*reached=*/true);
  last_prescribed_.resize(0);
  last_constrained_.clear();
  forced_step_limit_mm_ = 0.0;
  lag_mm_ = 0.0;
  catching_up_ = false;
}

}  // namespace vpm

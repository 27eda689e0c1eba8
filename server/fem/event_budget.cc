#include "server/fem/event_budget.h"

#include <algorithm>

namespace vpm {
namespace {

Eigen::VectorXd Gather(const Eigen::VectorXd& values, const std::vector<int32_t>& dofs) {
  Eigen::VectorXd out(static_cast<int64_t>(dofs.size()));
  for (size_t i = 0; i < dofs.size(); ++i) out[static_cast<int64_t>(i)] = values[dofs[i]];
  return out;
}

}  // namespace

void EventBudget::BeginSolve(const Eigen::VectorXd& prescribed_mm, const Eigen::VectorXd& force_n,
                             const std::vector<int32_t>& constrained) {
  Eigen::VectorXd target = Gather(prescribed_mm, constrained);
  // Exact comparison: a settle pass repeats the same offset, and any new
  // pointer position is a new load.
  const bool same = carrying_ && target.size() == carried_prescribed_.size() &&
                    target == carried_prescribed_ && force_n.size() == carried_force_.size() &&
                    force_n == carried_force_;
  if (!same) load_steps_ = 0;
  carried_prescribed_ = std::move(target);
  carried_force_ = force_n;
  carrying_ = true;
}

bool EventBudget::RoomForLoadStep(int used, int intermediate) const {
  return newton_iterations_ == 0 || used + intermediate + stop_iterations_ <= newton_iterations_;
}

int EventBudget::IterationsFor(int used, int limit) const {
  return newton_iterations_ == 0 ? limit : std::min(limit, newton_iterations_ - used);
}

void EventBudget::EndSolve(bool reached) {
  if (reached) Clear();
}

void EventBudget::Clear() {
  load_steps_ = 0;
  carrying_ = false;
  carried_prescribed_.resize(0);
  carried_force_.resize(0);
}

}  // namespace vpm

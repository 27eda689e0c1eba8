#include "server/fem/constrained_factor.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace vpm {
namespace {

// Smallest accepted pivot of the LDL^T factor relative to the diagonal entry
// of its row: a free rigid motion leaves a pivot at round-off level (~1e-16
// of it); stiffness contrasts and poorly shaped tets stay far above this.
constexpr double kMinRelativePivot = 1e-12;

}  // namespace

Result<ConstrainedFactor> ConstrainedFactor::Create(const Eigen::SparseMatrix<double>& stiffness,
                                                    const std::vector<uint8_t>& fixed,
                                                    HandleFactor handle_factor) {
  const int64_t n = stiffness.rows();
  if (stiffness.cols() != n || static_cast<int64_t>(fixed.size()) != n) {
    return absl::InvalidArgumentError(StrCat("stiffness is ", stiffness.rows(), " by ",
                                             stiffness.cols(), " with ", fixed.size(), " flags"));
  }
  ConstrainedFactor factor;
  factor.compact_.assign(n, -1);
  for (int64_t d = 0; d < n; ++d) {
    if (fixed[d]) continue;
    factor.compact_[d] = static_cast<int32_t>(factor.free_dofs_.size());
    factor.free_dofs_.push_back(static_cast<int32_t>(d));
  }
  const auto m = static_cast<int64_t>(factor.free_dofs_.size());
  if (m == 0) {
    return absl::FailedPreconditionError("every degree of freedom is fixed: nothing can move");
  }
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(stiffness.nonZeros());
  for (int64_t col = 0; col < n; ++col) {
    if (factor.compact_[col] < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(stiffness, col); it; ++it) {
      const int32_t row = factor.compact_[it.row()];
      if (row >= 0) triplets.emplace_back(row, factor.compact_[col], it.value());
    }
  }
  Eigen::SparseMatrix<double> free_block(m, m);
  free_block.setFromTriplets(triplets.begin(), triplets.end());
  factor.ldlt_ = std::make_unique<Ldlt>();
  factor.ldlt_->compute(free_block);
  const Eigen::VectorXd pivots = factor.ldlt_->vectorD();
  const Eigen::VectorXd diagonal = factor.ldlt_->permutationP() * free_block.diagonal();
  const bool singular = (pivots.array() <= kMinRelativePivot * diagonal.array()).any();
  if (factor.ldlt_->info() != Eigen::Success || singular) {
    return absl::FailedPreconditionError(
        "the constrained stiffness is singular: the fixed DOFs leave a rigid motion free "
        "(fix at least 3 non-collinear vertices, or the box corners)");
  }
  factor.panels_ = LdltPanels(*factor.ldlt_);
  factor.factor_nonzeros_ = factor.ldlt_->matrixL().nestedExpression().nonZeros() + m;
  factor.rc_.resize(m);
  factor.yc_.resize(m);
  factor.handle_factor_ = handle_factor;
  if (handle_factor == HandleFactor::kRefactor) factor.free_block_ = std::move(free_block);
  return factor;
}

Result<std::vector<int32_t>> ConstrainedFactor::CompactExtra(
    const std::vector<int32_t>& dofs) const {
  std::vector<int32_t> extra;
  extra.reserve(dofs.size());
  for (int32_t d : dofs) {
    if (d < 0 || d >= size() || compact_[d] < 0) {
      return absl::InvalidArgumentError(
          StrCat("extra constrained DOF ", d, " is out of range or already fixed"));
    }
    extra.push_back(compact_[d]);
  }
  std::vector<int32_t> sorted = extra;
  std::sort(sorted.begin(), sorted.end());
  if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
    return absl::InvalidArgumentError("extra constrained DOFs repeat");
  }
  return extra;
}

Status ConstrainedFactor::SetExtraFixed(const std::vector<int32_t>& dofs) {
  ASSIGN_OR_RETURN(std::vector<int32_t> extra, CompactExtra(dofs));
  springs_ = false;
  if (handle_factor_ == HandleFactor::kRefactor) return Refactor(std::move(extra), {});
  SetCapacitance(std::move(extra), {});
  return absl::OkStatus();
}

Status ConstrainedFactor::SetSprings(const std::vector<int32_t>& dofs,
                                     const std::vector<double>& stiffness_n_per_mm) {
  if (stiffness_n_per_mm.size() != dofs.size()) {
    return absl::InvalidArgumentError(StrCat("got ", stiffness_n_per_mm.size(),
                                             " spring stiffnesses for ", dofs.size(), " DOFs"));
  }
  for (double k : stiffness_n_per_mm) {
    if (!std::isfinite(k) || !(k > 0.0)) {
      return absl::InvalidArgumentError("spring stiffnesses must be finite and > 0 N/mm");
    }
  }
  ASSIGN_OR_RETURN(std::vector<int32_t> extra, CompactExtra(dofs));
  springs_ = true;
  if (handle_factor_ == HandleFactor::kRefactor) {
    return Refactor(std::move(extra), stiffness_n_per_mm);
  }
  SetCapacitance(std::move(extra), stiffness_n_per_mm);
  return absl::OkStatus();
}

void ConstrainedFactor::SetCapacitance(std::vector<int32_t> extra,
                                       const std::vector<double>& springs) {
  const auto m = static_cast<int64_t>(free_dofs_.size());
  const auto h = static_cast<int64_t>(extra.size());
  Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(m, h);
  for (int64_t j = 0; j < h; ++j) selector(extra[j], j) = 1.0;
  w_ = h > 0 ? Eigen::MatrixXd(ldlt_->solve(selector)) : Eigen::MatrixXd(m, 0);
  Eigen::MatrixXd c(h, h);
  for (int64_t j = 0; j < h; ++j) c.row(j) = w_.row(extra[j]);
  // Woodbury: (K + E k E^T)^-1 = K^-1 - W (diag(1/k) + C)^-1 W^T.
  for (size_t j = 0; j < springs.size(); ++j) c(j, j) += 1.0 / springs[j];
  // C is symmetric positive definite (a principal block of K_BB^-1, plus a
  // positive diagonal with springs).
  capacitance_inverse_ = c.llt().solve(Eigen::MatrixXd::Identity(h, h));
  extra_compact_ = std::move(extra);
}

Status ConstrainedFactor::Refactor(std::vector<int32_t> extra,
                                   const std::vector<double>& springs) {
  if (extra.empty()) {
    extra_compact_.clear();
    return absl::OkStatus();
  }
  std::vector<uint8_t> is_extra(free_dofs_.size(), 0);
  for (int32_t i : extra) is_extra[i] = 1;
  Eigen::SparseMatrix<double> matrix = free_block_;
  if (springs.empty()) {
    for (int64_t col = 0; col < matrix.outerSize(); ++col) {
      for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, col); it; ++it) {
        if (it.row() != col && (is_extra[it.row()] || is_extra[col])) it.valueRef() = 0.0;
      }
    }
  } else {
    for (size_t j = 0; j < extra.size(); ++j) matrix.coeffRef(extra[j], extra[j]) += springs[j];
  }
  if (!handle_ldlt_) {
    handle_ldlt_ = std::make_unique<Ldlt>();
    handle_ldlt_->analyzePattern(matrix);
  }
  handle_ldlt_->factorize(matrix);
  if (handle_ldlt_->info() != Eigen::Success) {
    extra_compact_.clear();
    return absl::FailedPreconditionError("the stiffness with the handles held did not factor");
  }
  handle_panels_ = LdltPanels(*handle_ldlt_);
  extra_compact_ = std::move(extra);
  return absl::OkStatus();
}

void ConstrainedFactor::Apply(const Eigen::VectorXd& r, bool with_extra, Eigen::VectorXd& z) const {
  const auto m = static_cast<int64_t>(free_dofs_.size());
  for (int64_t i = 0; i < m; ++i) rc_[i] = r[free_dofs_[i]];
  const bool extra = with_extra && !extra_compact_.empty();
  // Prescribed H: its right-hand side and solution are 0; springs keep both.
  const bool zero_extra = extra && !springs_;
  if (zero_extra) {
    for (int32_t i : extra_compact_) rc_[i] = 0.0;
  }
  if (extra && handle_factor_ == HandleFactor::kRefactor) {
    // Prescribed: H is decoupled and its right-hand side 0, so z_H comes out 0.
    handle_panels_.Solve(rc_, yc_);
    if (zero_extra) {
      for (int32_t i : extra_compact_) yc_[i] = 0.0;
    }
  } else {
    panels_.Solve(rc_, yc_);
  }
  if (extra && handle_factor_ == HandleFactor::kCapacitance) {
    Eigen::VectorXd y_h(extra_compact_.size());
    for (size_t j = 0; j < extra_compact_.size(); ++j) y_h[j] = yc_[extra_compact_[j]];
    yc_.noalias() -= w_ * (capacitance_inverse_ * y_h);
    if (zero_extra) {
      for (int32_t i : extra_compact_) yc_[i] = 0.0;
    }
  }
  z.setZero(size());
  for (int64_t i = 0; i < m; ++i) z[free_dofs_[i]] = yc_[i];
}

}  // namespace vpm

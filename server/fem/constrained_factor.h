// The rest stiffness factored once per topology, usable as an exact inverse
// for any extra set of prescribed DOFs (the grab handles) without
// refactoring.
//
// The factor covers the base free set B (all DOFs not in `fixed`). For extra
// constrained DOFs H inside B, the inverse on S = B \ H follows from the
// base factor by a capacitance (Schur complement) correction:
//   y = K_BB^-1 [r_S; 0],  W = K_BB^-1 E_H,  C = E_H^T W = (K_BB^-1)_HH,
//   z = y - W C^-1 y_H   (then z_H = 0 and K_SS z_S = r_S).
// Setting H costs |H| solves with the factor; each application one solve
// plus a #B by |H| product (HandleFactor::kCapacitance).
//
// Or (HandleFactor::kRefactor) a second factor of K_BB with H's rows and
// columns decoupled (off-diagonal entries 0, the pattern kept), whose
// symbolic analysis is made once and whose numeric factorization is redone
// per H: setting H costs one numeric factorization, each application one
// solve. Both give the same z to round-off (ConstrainedFactor tests);
// bench/drag_loop_bench.cc --handle-factor measures which is faster.
//
// Or H held by springs instead of prescribed (SetSprings): the inverse of
// K_BB + E_H diag(k) E_H^T on all of B, by the same two routes (kRefactor:
// k added to H's diagonal, numeric factorization on the same analysis;
// kCapacitance: Woodbury, C = diag(1/k) + (K_BB^-1)_HH).
enum class HandleFactor { kCapacitance, kRefactor };
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "server/common/status.h"
#include "server/fem/ldlt_panels.h"

namespace vpm {

class ConstrainedFactor {
 public:
  // Factors the free block of `stiffness` with SimplicialLDLT (AMD order).
  //   stiffness  n by n symmetric (both triangles or the lower one), N/mm
  //   fixed      n flags, 1 = constrained
  // Fails with FailedPrecondition when the free block is not positive
  // definite (constraints leave a rigid motion free), InvalidArgument on a
  // size mismatch.
  static Result<ConstrainedFactor> Create(const Eigen::SparseMatrix<double>& stiffness,
                                          const std::vector<uint8_t>& fixed,
                                          HandleFactor handle_factor = HandleFactor::kRefactor);

  // Replaces the extra constrained DOFs H (indices into the n DOFs, each
  // free in `fixed`, no repeats); empty clears them. Fails (InvalidArgument)
  // on a bad index, leaving the previous set; FailedPrecondition when the
  // decoupled factor fails (kRefactor; not expected: a principal block of a
  // positive definite matrix is positive definite).
  Status SetExtraFixed(const std::vector<int32_t>& dofs);
  // Replaces H by spring-held DOFs: `dofs` as for SetExtraFixed, with
  // stiffness_n_per_mm[j] > 0 (finite) added to dofs[j]'s diagonal. Apply
  // with with_extra then inverts K_BB + diag(k) on every free DOF.
  Status SetSprings(const std::vector<int32_t>& dofs,
                    const std::vector<double>& stiffness_n_per_mm);

  // z = K_SS^-1 r_S on S = free DOFs minus (with_extra ? H : none), 0 on
  // every other DOF. r, z: n (z resized). Entries of r outside S are ignored.
  // With springs (SetSprings) and with_extra: z = (K_BB + diag(k))^-1 r_B.
  void Apply(const Eigen::VectorXd& r, bool with_extra, Eigen::VectorXd& z) const;

  // An empty factor (size 0); use Create.
  ConstrainedFactor() = default;

  int64_t size() const { return static_cast<int64_t>(compact_.size()); }
  int64_t free_count() const { return static_cast<int64_t>(free_dofs_.size()); }
  int64_t factor_nonzeros() const { return factor_nonzeros_; }

 private:
  using Ldlt = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>;
  // H as compact indices, checked (InvalidArgument on a bad or repeated DOF).
  Result<std::vector<int32_t>> CompactExtra(const std::vector<int32_t>& dofs) const;
  // kRefactor: factors the free block with H decoupled (springs empty) or
  // with springs[j] added to H[j]'s diagonal.
  Status Refactor(std::vector<int32_t> extra, const std::vector<double>& springs);
  // kCapacitance: W and C^-1, C = (K_BB^-1)_HH (+ diag(1/k) with springs).
  void SetCapacitance(std::vector<int32_t> extra, const std::vector<double>& springs);

  std::vector<int32_t> free_dofs_;  // compact index -> DOF
  std::vector<int32_t> compact_;    // DOF -> compact index, -1 if fixed
  std::unique_ptr<Ldlt> ldlt_;
  LdltPanels panels_;  // ldlt_'s solve, by panels (ldlt_panels.h)
  int64_t factor_nonzeros_ = 0;
  HandleFactor handle_factor_ = HandleFactor::kRefactor;
  // kRefactor: the free block, and its factor with H decoupled (symbolic
  // analysis at the first SetExtraFixed, numeric at each).
  Eigen::SparseMatrix<double> free_block_;
  std::unique_ptr<Ldlt> handle_ldlt_;
  LdltPanels handle_panels_;  // handle_ldlt_'s solve, by panels
  std::vector<int32_t> extra_compact_;   // H as compact indices
  bool springs_ = false;                 // H is spring-held (SetSprings)
  Eigen::MatrixXd w_;                    // #B by |H|
  Eigen::MatrixXd capacitance_inverse_;  // C^-1, |H| by |H|
  mutable Eigen::VectorXd rc_, yc_;      // scratch, #B
};

}  // namespace vpm

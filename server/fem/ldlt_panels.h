// The solve of a sparse LDL^T factor (Eigen's SimplicialLDLT), regrouped
// into panels: runs of up to kMaxPanelColumns consecutive columns of L whose
// rows below the run are the same. AMD orders the 3 DOFs of a vertex
// together (they have one adjacency), so most columns of the FEM factor
// fall into panels of 3 or more. The forward solve then loads and stores a
// row below a panel once for its k columns instead of k times, and the
// backward solve reads each column's rows from one contiguous block. The
// same floating-point operations as Eigen's solve in the same order: the
// same result bit for bit (up to the sign of a zero where L has no entry
// inside a panel), so the FEM takes exactly the path it took with Eigen's
// solve. The backward solve stays one dependent chain of subtractions per
// column, as Eigen's; summing a panel's columns together halves the solve
// again but changes its rounding (docs/benchmarks/DRAG_LOOP.md).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

namespace vpm {

class LdltPanels {
 public:
  using Ldlt = Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>;
  static constexpr int kMaxPanelColumns = 8;

  // An empty solve (size 0).
  LdltPanels() = default;
  // The panels of `ldlt`'s factor, which must hold a successful
  // factorization (info() == Success), m by m.
  explicit LdltPanels(const Ldlt& ldlt);

  // x = A^-1 b for the factored A: P^T L^-T D^-1 L^-1 P b.
  //   b  m entries; x resized to m (may not alias b)
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

  int64_t size() const { return static_cast<int64_t>(inverse_diagonal_.size()); }
  int64_t panel_count() const { return static_cast<int64_t>(panels_.size()); }

 private:
  struct Panel {
    int32_t first_column = 0;
    int32_t columns = 0;       // k, 1..kMaxPanelColumns
    int64_t first_row = 0;     // into rows_
    int32_t row_count = 0;     // rows below the panel
    int64_t first_value = 0;   // into values_: k x k triangle, then row_count x k
  };
  template <int K>
  void Forward(const Panel& panel, double* x) const;
  template <int K>
  void Backward(const Panel& panel, double* x) const;

  std::vector<Panel> panels_;
  std::vector<int32_t> rows_;
  // Per panel: the strictly lower k x k triangle within the panel (row-major,
  // dense, zeros where L has none), then the rows below the panel column by
  // column (row_count values per column).
  std::vector<double> values_;
  Eigen::VectorXd inverse_diagonal_;  // 1 / D
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> p_, p_inverse_;
  mutable Eigen::VectorXd scratch_;
};

}  // namespace vpm

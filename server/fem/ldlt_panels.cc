#include "server/fem/ldlt_panels.h"

#include <algorithm>
#include <type_traits>
#include <utility>

namespace vpm {
namespace {

using Factor = Eigen::SparseMatrix<double>;

// Row indices of column j of L (strictly lower, ascending) and their values.
struct Column {
  const int* rows = nullptr;
  const double* values = nullptr;
  int64_t count = 0;
};

Column ColumnOf(const Factor& l, int64_t j) {
  const int64_t begin = l.outerIndexPtr()[j];
  const int64_t count = l.innerNonZeroPtr() != nullptr ? l.innerNonZeroPtr()[j]
                                                        : l.outerIndexPtr()[j + 1] - begin;
  return {l.innerIndexPtr() + begin, l.valuePtr() + begin, count};
}

// The entries of `c` with row > last.
Column Below(const Column& c, int64_t last) {
  const int* start = std::upper_bound(c.rows, c.rows + c.count, static_cast<int>(last));
  const int64_t skipped = start - c.rows;
  return {start, c.values + skipped, c.count - skipped};
}

// run(std::integral_constant<int, k>{}) for k = width, one of Ks + 1.
template <typename Run, int... Ks>
void WithWidth(int width, const Run& run, std::integer_sequence<int, Ks...>) {
  (void)((width == Ks + 1 ? (run(std::integral_constant<int, Ks + 1>{}), true) : false) || ...);
}

bool SameRows(const Column& a, const Column& b) {
  return a.count == b.count && std::equal(a.rows, a.rows + a.count, b.rows);
}

}  // namespace

LdltPanels::LdltPanels(const Ldlt& ldlt) {
  const Factor& l = ldlt.matrixL().nestedExpression();
  const int64_t m = l.cols();
  inverse_diagonal_ = ldlt.vectorD().cwiseInverse();
  p_ = ldlt.permutationP();
  p_inverse_ = ldlt.permutationPinv();
  scratch_.resize(m);
  for (int64_t j = 0; j < m;) {
    // Grow the panel while every column has the rows of the first below it.
    int k = 1;
    while (k < kMaxPanelColumns && j + k < m) {
      const int64_t last = j + k;  // the candidate panel's last column
      const Column first = Below(ColumnOf(l, j), last);
      bool same = true;
      for (int c = 1; c <= k && same; ++c) {
        same = SameRows(first, Below(ColumnOf(l, j + c), last));
      }
      if (!same) break;
      ++k;
    }
    Panel panel;
    panel.first_column = static_cast<int32_t>(j);
    panel.columns = k;
    panel.first_row = static_cast<int64_t>(rows_.size());
    panel.first_value = static_cast<int64_t>(values_.size());
    const Column below = Below(ColumnOf(l, j), j + k - 1);
    panel.row_count = static_cast<int32_t>(below.count);
    rows_.insert(rows_.end(), below.rows, below.rows + below.count);
    values_.resize(values_.size() + size_t(k) * k + size_t(below.count) * k, 0.0);
    double* triangle = values_.data() + panel.first_value;
    double* rows = triangle + k * k;
    for (int c = 0; c < k; ++c) {
      const Column column = ColumnOf(l, j + c);
      int64_t r = 0;
      for (int64_t e = 0; e < column.count; ++e) {
        const int64_t row = column.rows[e];
        if (row <= j + k - 1) {
          triangle[(row - j) * k + c] = column.values[e];
        } else {
          rows[c * below.count + r++] = column.values[e];  // rows in `below`'s order
        }
      }
    }
    panels_.push_back(panel);
    j += k;
  }
}

// Both passes do Eigen's floating-point operations in Eigen's order
// (SparseCore/TriangularSolver.h), so the result is Eigen's bit for bit (a
// structural zero inside a panel subtracts a signed 0):
// forward, each x[i] takes x[i] - L(i, j) x_j column by column, ascending,
// skipping the columns whose x_j is 0; backward, each x_j starts from y_j
// and takes - L(r, j) x_r row by row, ascending (the panel's own rows
// first). Only the memory traffic changes: forward, a row below the panel
// is loaded and stored once for its k columns; backward, the panel's row
// indices and values are read from one contiguous block per column.
template <int K>
void LdltPanels::Forward(const Panel& panel, double* x) const {
  const double* triangle = values_.data() + panel.first_value;
  const double* values = triangle + K * K;
  double* xs = x + panel.first_column;
  for (int c = 0; c < K; ++c) {
    if (xs[c] == 0.0) continue;
    for (int r = c + 1; r < K; ++r) xs[r] -= xs[c] * triangle[r * K + c];
  }
  double v[K];
  bool any_zero = false;
  for (int c = 0; c < K; ++c) {
    v[c] = xs[c];
    any_zero = any_zero || v[c] == 0.0;
  }
  const int32_t* rows = rows_.data() + panel.first_row;
  if (!any_zero) {
    for (int32_t i = 0; i < panel.row_count; ++i) {
      double xi = x[rows[i]];
      for (int c = 0; c < K; ++c) xi -= v[c] * values[c * panel.row_count + i];
      x[rows[i]] = xi;
    }
    return;
  }
  for (int32_t i = 0; i < panel.row_count; ++i) {
    double xi = x[rows[i]];
    for (int c = 0; c < K; ++c) {
      if (v[c] != 0.0) xi -= v[c] * values[c * panel.row_count + i];
    }
    x[rows[i]] = xi;
  }
}

template <int K>
void LdltPanels::Backward(const Panel& panel, double* x) const {
  const double* triangle = values_.data() + panel.first_value;
  const double* values = triangle + K * K;
  const int32_t* rows = rows_.data() + panel.first_row;
  double* xs = x + panel.first_column;
  for (int c = K - 1; c >= 0; --c) {
    double tmp = xs[c];
    for (int r = c + 1; r < K; ++r) tmp -= triangle[r * K + c] * xs[r];
    const double* column = values + c * panel.row_count;
    for (int32_t i = 0; i < panel.row_count; ++i) tmp -= column[i] * x[rows[i]];
    xs[c] = tmp;
  }
}

void LdltPanels::Solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  scratch_.noalias() = p_ * b;
  double* y = scratch_.data();
  // One instantiation per panel width, so the k-loops unroll.
  auto dispatch = [](const Panel& panel, auto run) {
    WithWidth(panel.columns, run, std::make_integer_sequence<int, kMaxPanelColumns>{});
  };
  for (const Panel& panel : panels_) {
    dispatch(panel, [&](auto k) { Forward<decltype(k)::value>(panel, y); });
  }
  scratch_.array() *= inverse_diagonal_.array();
  for (auto it = panels_.rbegin(); it != panels_.rend(); ++it) {
    dispatch(*it, [&](auto k) { Backward<decltype(k)::value>(*it, y); });
  }
  x.noalias() = p_inverse_ * scratch_;
}

}  // namespace vpm

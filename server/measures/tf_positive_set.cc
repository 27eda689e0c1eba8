#include "server/measures/tf_positive_set.h"

#include <limits>

namespace vpm {

TfPositiveSet::TfPositiveSet(const TransferFunction& tf) {
  std::vector<double> breaks;
  for (const TfPoint& p : tf.points()) {
    if (breaks.empty() || p.value != breaks.back()) breaks.push_back(p.value);
  }
  const double inf = std::numeric_limits<double>::infinity();
  // Pieces in order: (-inf, b0), {b0}, (b0, b1), {b1}, ..., {bn}, (bn, inf).
  struct Piece {
    double lo, hi;
    bool is_point;
    bool positive;
  };
  std::vector<Piece> pieces;
  pieces.push_back({-inf, breaks.front(), false, tf.points().front().cost > 0.0});
  for (size_t m = 0; m < breaks.size(); ++m) {
    pieces.push_back({breaks[m], breaks[m], true, tf.Evaluate(breaks[m]) > 0.0});
    const double next = m + 1 < breaks.size() ? breaks[m + 1] : inf;
    const bool positive = m + 1 < breaks.size()
                              ? tf.Evaluate(breaks[m] + 0.5 * (next - breaks[m])) > 0.0
                              : tf.points().back().cost > 0.0;
    pieces.push_back({breaks[m], next, false, positive});
  }
  for (const Piece& piece : pieces) {
    if (!piece.positive) continue;
    // A piece continues the last range when they touch: a point after an
    // open interval ending there, or an open interval after its start point.
    if (!ranges_.empty() && ranges_.back().hi == piece.lo &&
        (piece.is_point || ranges_.back().hi_closed)) {
      ranges_.back().hi = piece.hi;
      ranges_.back().hi_closed = piece.is_point;
      continue;
    }
    ranges_.push_back({piece.lo, piece.hi, piece.is_point, piece.is_point});
  }
}

}  // namespace vpm

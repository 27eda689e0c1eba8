// The set {value : TF(value) > 0} of a transfer function as a few ranges, so
// per-voxel tests over millions of voxels cost a comparison or two.
#pragma once

#include <vector>

#include "server/volume/transfer_function.h"

namespace vpm {

class TfPositiveSet {
 public:
  // Exactly the values where tf.Evaluate(value) > 0: TF is piecewise linear
  // with costs >= 0, so its positivity only changes at control point values;
  // each control value and each open piece between them is classified with
  // tf.Evaluate itself, then adjacent positive pieces are merged. The one
  // difference: within about 1e-308 of a control value TF's own arithmetic
  // underflows to 0 where the exact TF is positive; this set says positive.
  explicit TfPositiveSet(const TransferFunction& tf);

  bool Contains(double value) const {
    for (const Range& r : ranges_) {
      if ((value > r.lo || (r.lo_closed && value == r.lo)) &&
          (value < r.hi || (r.hi_closed && value == r.hi))) {
        return true;
      }
    }
    return false;
  }

  // A maximal run of positive values; lo may be -inf and hi +inf.
  struct Range {
    double lo;
    double hi;
    bool lo_closed;
    bool hi_closed;
  };
  const std::vector<Range>& ranges() const { return ranges_; }

 private:
  std::vector<Range> ranges_;
};

}  // namespace vpm

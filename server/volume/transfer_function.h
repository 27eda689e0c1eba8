// The transfer cost TF(value) of docs/ALGORITHM.md section 1: piecewise linear
// through control points (value, cost) sorted by value, clamped to the first
// and last cost outside them.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "server/common/status.h"
#include "server/volume/volume.h"

namespace vpm {

// The preset chosen by the image: ct-soft-tissue on CT in HU, mri-t1 on
// other volumes (IsCtInHu, ct_in_hu.h).
inline constexpr std::string_view kAutoTransferCost = "auto";

struct TfPoint {
  double value;  // image value (HU for CT)
  double cost;   // in [0, 1]
};

class TransferFunction {
 public:
  // At least one point; values finite and non-decreasing after sorting;
  // costs finite in [0, 1].
  static Result<TransferFunction> Create(std::vector<TfPoint> points);
  // "v:c,v:c,..." (values in the volume's units).
  static Result<TransferFunction> Parse(std::string_view text);
  // A named preset (see PresetNames(); "auto" picks one by `volume`) or a
  // "v:c,..." list. Presets defined on intensity percentiles (mri-t1) are
  // resolved against `volume`.
  static Result<TransferFunction> FromSpec(std::string_view spec, const Volume& volume);
  // The docs/ALGORITHM.md default, `ct-soft-tissue`.
  static TransferFunction CtSoftTissue();

  // Preset names with a one-line description each, for --help.
  static std::vector<std::pair<std::string, std::string>> PresetNames();

  double Evaluate(double value) const;
  const std::vector<TfPoint>& points() const { return points_; }
  std::string ToString() const;

 private:
  explicit TransferFunction(std::vector<TfPoint> points) : points_(std::move(points)) {}
  std::vector<TfPoint> points_;
};

}  // namespace vpm

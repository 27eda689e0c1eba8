#include "server/volume/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "server/volume/ct_in_hu.h"

namespace vpm {
namespace {

// Percentile-defined control points: (percentile in [0,100], cost).
const std::vector<TfPoint> kMriT1Percentiles = {
    {2.0, 0.0}, {20.0, 0.2}, {50.0, 0.8}, {90.0, 1.0}, {99.5, 0.6}};

double Percentile(std::vector<float>& sorted, double p) {
  const double pos = p / 100.0 * static_cast<double>(sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

TransferFunction ResolvePercentiles(const Volume& volume) {
  // A strided sample of at most ~1M voxels is plenty for percentiles.
  const VoxelValues& values = volume.voxels();
  const int64_t count = values.size();
  const int64_t stride = std::max<int64_t>(1, count / (1 << 20));
  std::vector<float> sample;
  sample.reserve(static_cast<size_t>(count / stride + 1));
  for (int64_t n = 0; n < count; n += stride) sample.push_back(values[n]);
  std::sort(sample.begin(), sample.end());
  std::vector<TfPoint> points;
  double last = -INFINITY;
  for (const TfPoint& p : kMriT1Percentiles) {
    // Strictly increasing so that flat images still give a valid function.
    double v = Percentile(sample, p.value);
    if (v <= last) v = last + 1e-3;
    points.push_back({v, p.cost});
    last = v;
  }
  return *TransferFunction::Create(points);
}

}  // namespace

Result<TransferFunction> TransferFunction::Create(std::vector<TfPoint> points) {
  if (points.empty()) return absl::InvalidArgumentError("transfer function has no points");
  for (const TfPoint& p : points) {
    if (!std::isfinite(p.value) || !std::isfinite(p.cost) || p.cost < 0.0 || p.cost > 1.0) {
      return absl::InvalidArgumentError(StrCat("transfer function point (", p.value, ", ",
                                                     p.cost,
                                                     "): value must be finite and cost in [0,1]"));
    }
  }
  std::stable_sort(points.begin(), points.end(),
                   [](const TfPoint& a, const TfPoint& b) { return a.value < b.value; });
  return TransferFunction(std::move(points));
}

Result<TransferFunction> TransferFunction::Parse(std::string_view text) {
  std::vector<TfPoint> points;
  const std::string text_copy(text);
  for (absl::string_view item : absl::StrSplit(text_copy, ',', absl::SkipWhitespace())) {
    std::vector<absl::string_view> vc = absl::StrSplit(item, ':');
    TfPoint p{};
    if (vc.size() != 2 || !absl::SimpleAtod(absl::StripAsciiWhitespace(vc[0]), &p.value) ||
        !absl::SimpleAtod(absl::StripAsciiWhitespace(vc[1]), &p.cost)) {
      return absl::InvalidArgumentError(
          StrCat("transfer function item '", item, "' is not VALUE:COST"));
    }
    points.push_back(p);
  }
  return Create(std::move(points));
}

TransferFunction TransferFunction::CtSoftTissue() {
  return *Create({{-1000, 0}, {-200, 0}, {-100, 0.3}, {20, 0.8},
                  {60, 1.0}, {300, 1.0}, {700, 0.5}, {3000, 0.5}});
}

std::vector<std::pair<std::string, std::string>> TransferFunction::PresetNames() {
  return {
      {"auto", "by the image: ct-soft-tissue on CT in HU, mri-t1 otherwise (ct_in_hu.h)"},
      {"ct-soft-tissue", "CT default (docs/ALGORITHM.md): fat to soft tissue high, bone half"},
      {"ct-vessels", "CT angiography: contrast-filled vessels (150-300 HU) highest"},
      {"ct-bone", "CT bone: cancellous and cortical bone (>= 250 HU) highest"},
      {"mri-t1",
       "MRI T1: on the volume's own intensity percentiles (p2 0, p20 0.2, "
       "p50 0.8, p90 1, p99.5 0.6)"},
  };
}

Result<TransferFunction> TransferFunction::FromSpec(std::string_view spec, const Volume& volume) {
  if (spec == kAutoTransferCost) spec = IsCtInHu(volume) ? "ct-soft-tissue" : "mri-t1";
  if (spec == "ct-soft-tissue") return CtSoftTissue();
  if (spec == "ct-vessels") {
    return Create({{-1000, 0}, {100, 0}, {150, 0.6}, {200, 1.0}, {300, 1.0}, {400, 0.3},
                   {3000, 0.3}});
  }
  if (spec == "ct-bone") return Create({{-1000, 0}, {150, 0}, {250, 0.6}, {400, 1.0}, {3000, 1.0}});
  if (spec == "mri-t1") return ResolvePercentiles(volume);
  if (spec.find(':') != std::string_view::npos) return Parse(spec);
  std::string names;
  for (const auto& [name, _] : PresetNames()) StrAppend(&names, names.empty() ? "" : ", ", name);
  return absl::InvalidArgumentError(StrCat("unknown transfer function '", spec,
                                                 "': use a preset (", names,
                                                 ") or VALUE:COST,VALUE:COST,..."));
}

double TransferFunction::Evaluate(double value) const {
  // Right-continuous at repeated values (steps): a value equal to a step's
  // position takes the cost after the step.
  if (value < points_.front().value) return points_.front().cost;
  if (value >= points_.back().value) return points_.back().cost;
  // First point with a value greater than `value`; its predecessor is <=.
  auto hi = std::upper_bound(points_.begin(), points_.end(), value,
                             [](double v, const TfPoint& p) { return v < p.value; });
  auto lo = hi - 1;
  const double t = (value - lo->value) / (hi->value - lo->value);
  return lo->cost + t * (hi->cost - lo->cost);
}

std::string TransferFunction::ToString() const {
  std::string s;
  for (const TfPoint& p : points_) StrAppend(&s, s.empty() ? "" : ",", p.value, ":", p.cost);
  return s;
}

}  // namespace vpm

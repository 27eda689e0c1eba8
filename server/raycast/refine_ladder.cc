#include "server/raycast/refine_ladder.h"

namespace vpm {

std::vector<double> RefineLadder(const RenderRequest& interactive, const VolumeGeometry& geometry,
                                 std::span<const double> multiples) {
  RenderRequest still = interactive;
  still.quality = RenderQuality::kStill;
  const double still_step_mm = RequestStepMm(still, geometry);
  const double moving_step_mm = RequestStepMm(interactive, geometry);
  const int64_t moving_rays = int64_t(RenderSide(interactive, interactive.width)) *
                              RenderSide(interactive, interactive.height);
  const int64_t rung_rays = int64_t(still.width) * still.height;
  constexpr double kTolerance = 1e-9;  // relative, for steps (mm) that are equal
  std::vector<double> ladder;
  for (const double multiple : multiples) {
    if (!(multiple > 1.0) || (!ladder.empty() && multiple >= ladder.back())) continue;
    const double step_mm = multiple * still_step_mm;
    const bool finer = step_mm < moving_step_mm * (1.0 - kTolerance);
    const bool as_fine = step_mm <= moving_step_mm * (1.0 + kTolerance);
    if (rung_rays >= moving_rays && as_fine && (rung_rays > moving_rays || finer)) {
      ladder.push_back(multiple);
    }
  }
  return ladder;
}

bool StillWorthRungs(double predicted_still_ms, double min_still_ms) {
  return !(min_still_ms > 0.0) || predicted_still_ms < 0.0 || predicted_still_ms >= min_still_ms;
}

void MakeRefineRung(RenderRequest& still, double multiple, const VolumeGeometry& geometry) {
  if (!(multiple > 1.0)) return;
  still.settings.step_mm = multiple * RequestStepMm(still, geometry);
}

}  // namespace vpm

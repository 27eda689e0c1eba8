// Progressive refinement at rest: once the pointer rests, a stream sends
// rungs of rising quality before the still (server/service/frame_stream.h).
// A rung is the still's own cast (full resolution, the still's bricks,
// bands and jitter seed) at a multiple of the still's step, so that it
// differs from the still by the step alone. The ladder keeps only the rungs
// that beat the interactive frames they follow: as many rays or more and a
// step as fine or finer, one of the two strictly (docs/RENDERING.md,
// "Interactive quality"; docs/benchmarks/INTERACTIVE_QUALITY.md measures
// each rung).
#pragma once

#include <array>
#include <span>
#include <vector>

#include "server/raycast/render_request.h"

namespace vpm {

// The rungs' steps as multiples of the still's, coarsest first (each > 1).
inline constexpr std::array<double, 1> kRefineStepMultiples = {2.0};

// The rungs (step multiples of the still's, coarsest first) to send after
// interactive frames cast as `interactive` (a kInteractive request whose
// settings.step_mm, when set, is the still's step too): those of
// `multiples` that beat it. Empty when none does (the sharp setting: full
// resolution at 1.5 x the still's step).
std::vector<double> RefineLadder(const RenderRequest& interactive, const VolumeGeometry& geometry,
                                 std::span<const double> multiples = kRefineStepMultiples);

// Whether a still predicted to cast in `predicted_still_ms` (-1: not known
// yet) is worth rungs before it: a rung (2 x the still's step) costs more
// than half the still, so where the still comes soon it only puts it off.
// True when min_still_ms <= 0 (always), when the prediction is unknown, or
// when it is at least min_still_ms (ServerOptions::refine_min_still_ms).
bool StillWorthRungs(double predicted_still_ms, double min_still_ms);

// Makes `still` (a kStill request) the rung at `multiple` x its step (mm:
// settings.step_mm); a multiple <= 1 leaves the still.
void MakeRefineRung(RenderRequest& still, double multiple, const VolumeGeometry& geometry);

}  // namespace vpm

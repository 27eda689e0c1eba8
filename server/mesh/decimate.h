// Step 2 of docs/ALGORITHM.md: remove the cheapest lattice vertex again and again
// until `target` vertices remain (the 8 anchors counted), updating the
// density of the neighbours of each removed vertex.
//
//   dens(v)   = sum over alive u != v with |p_u - p_v| < R of 1/|p_u - p_v|
//   Cd(v)     = dens(v) / D0,  D0 = max dens on the full initial lattice
//   Ctotal(v) = Ci(v) * (wg * Cg(v) + wd * S(v)),  S = 1 - Cd (spread) or Cd (paper)
// Ties in Ctotal go to the smaller linear id. Anchors are not inputs here:
// they are never removed and never counted in density.
//
// DecimateFast is O(N log N) (indexed heap, uniform grid of cell size R);
// DecimateNaive is the paper's O(N^2) scan, the reference. Both sum densities
// in increasing neighbour id and compute distances identically, so they make
// bit-identical decisions.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "server/common/cancel_token.h"
#include "server/common/status.h"

namespace vpm {

enum class DensityMode { kSpread, kPaper };
const char* DensityModeName(DensityMode m);  // "spread", "paper"
Result<DensityMode> ParseDensityMode(std::string_view name);

inline constexpr int64_t kAnchorCount = 8;

struct DecimationParams {
  int64_t target = 250;  // vertices to keep, anchors included
  double wg = 1.0;       // weight of the gradient term
  double wd = 0.5;       // weight of the spreading term
  double radius_mm = 0;  // density radius R (radius_factor * h), > 0
  DensityMode density_mode = DensityMode::kSpread;
  // Threads for the neighbour search in DecimateFast, 0..256; 0: one per
  // hardware thread, at most 8. The results do not depend on it.
  int threads = 0;
};

// DecimateFast gives each neighbour-search thread at least this many points
// (fewer would spend more on starting threads than they save).
inline constexpr int64_t kMinPointsPerSearchThread = 16384;

struct DecimationInput {
  std::vector<glm::dvec3> positions;  // #N lattice vertex positions, mm
  std::vector<double> ci;             // #N intensity cost in [0,1]
  std::vector<double> cg;             // #N normalised gradient cost in [0,1]
};

struct DecimationResult {
  std::vector<int64_t> kept;           // surviving lattice ids, ascending
  std::vector<double> kept_cost;       // Ctotal of each kept vertex when removal stopped
  std::vector<int64_t> removal_order;  // removed ids, first removed first
  double d0 = 0.0;                     // D0 (1/mm)
};

// `cancel` is polled every 1,024 removals: a cancelled call returns
// its status within milliseconds.
Result<DecimationResult> DecimateFast(const DecimationInput& input,
                                      const DecimationParams& params,
                                      const CancelToken& cancel = {});
Result<DecimationResult> DecimateNaive(const DecimationInput& input,
                                       const DecimationParams& params);

}  // namespace vpm

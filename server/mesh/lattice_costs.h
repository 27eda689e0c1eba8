// Step 1 of docs/ALGORITHM.md: the image terms of every lattice vertex.
//  - point footprint: Ci = TF(I[voxel(v)]), g = |grad I| at voxel(v);
//  - cell footprint:  Ci = mean of TF(I) over the vertex's cell,
//                     g = max of |grad I| over the cell.
// |grad I| is the central difference of section 1 (value/mm, clamped).
// This file is the CPU reference (double precision); LatticeCostsGpu computes
// the same on the GPU in float.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/mesh/lattice.h"
#include "server/volume/transfer_function.h"
#include "server/volume/volume.h"

namespace vpm {

enum class Footprint { kPoint, kCell };
const char* FootprintName(Footprint f);  // "point", "cell"
Result<Footprint> ParseFootprint(std::string_view name);

struct LatticeCosts {
  // One entry per lattice vertex, indexed by linear id. Ci in [0,1]; g in value/mm.
  std::vector<double> ci_cell, g_cell, ci_point, g_point;

  // n zero entries in each array.
  static LatticeCosts Zeros(size_t n) {
    return {std::vector<double>(n), std::vector<double>(n), std::vector<double>(n),
            std::vector<double>(n)};
  }

  const std::vector<double>& ci(Footprint f) const { return f == Footprint::kCell ? ci_cell : ci_point; }
  const std::vector<double>& g(Footprint f) const { return f == Footprint::kCell ? g_cell : g_point; }
};

// |grad I| at one voxel in double precision (value/mm).
double GradientMagnitudeAtD(const Volume& volume, int64_t i, int64_t j, int64_t k);

// Both footprints for every vertex of `lattice`, on `threads` CPU threads.
LatticeCosts EvaluateLatticeCostsCpu(const Volume& volume, const Lattice& lattice,
                                     const TransferFunction& tf, int threads = 2);

// Both footprints for the vertices `ids` of `lattice` only (step 4 scores a
// few hundred candidates of a finer lattice). Output entries follow `ids`.
LatticeCosts EvaluateVertexCostsCpu(const Volume& volume, const Lattice& lattice,
                                    const TransferFunction& tf, std::span<const int64_t> ids);

// Cg(v) = g(v) / max_u g(u), 0 where the max is 0. Output: same length as g.
std::vector<double> NormalizeGradientCost(const std::vector<double>& g);

}  // namespace vpm

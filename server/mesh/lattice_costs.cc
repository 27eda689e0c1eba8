#include "server/mesh/lattice_costs.h"

#include <algorithm>
#include <cmath>

#include "server/common/parallel_chunks.h"

namespace vpm {

const char* FootprintName(Footprint f) { return f == Footprint::kCell ? "cell" : "point"; }

Result<Footprint> ParseFootprint(std::string_view name) {
  if (name == "cell") return Footprint::kCell;
  if (name == "point") return Footprint::kPoint;
  return absl::InvalidArgumentError(StrCat("footprint '", name, "': use cell or point"));
}

double GradientMagnitudeAtD(const Volume& v, int64_t i, int64_t j, int64_t k) {
  const glm::dvec3& s = v.spacing_mm();
  const double gx = (double(v.AtClamped(i + 1, j, k)) - v.AtClamped(i - 1, j, k)) / (2.0 * s.x);
  const double gy = (double(v.AtClamped(i, j + 1, k)) - v.AtClamped(i, j - 1, k)) / (2.0 * s.y);
  const double gz = (double(v.AtClamped(i, j, k + 1)) - v.AtClamped(i, j, k - 1)) / (2.0 * s.z);
  return std::sqrt(gx * gx + gy * gy + gz * gz);
}

namespace {

// Cell footprint of one vertex: mean TF and max |grad I| over its cell.
void CellCosts(const Volume& volume, const Lattice& lattice, const TransferFunction& tf,
               int64_t id, double* ci, double* g) {
  const auto c = lattice.Coords(id);
  const auto ri = lattice.CellRange(0, c[0]), rj = lattice.CellRange(1, c[1]);
  const auto rk = lattice.CellRange(2, c[2]);
  double sum = 0.0, max_g = 0.0;
  for (int64_t k = rk[0]; k < rk[1]; ++k)
    for (int64_t j = rj[0]; j < rj[1]; ++j)
      for (int64_t i = ri[0]; i < ri[1]; ++i) {
        sum += tf.Evaluate(volume.At(i, j, k));
        max_g = std::max(max_g, GradientMagnitudeAtD(volume, i, j, k));
      }
  const double count = double(ri[1] - ri[0]) * double(rj[1] - rj[0]) * double(rk[1] - rk[0]);
  *ci = sum / count;
  *g = max_g;
}

void PointCosts(const Volume& volume, const Lattice& lattice, const TransferFunction& tf,
                int64_t id, double* ci, double* g) {
  const auto v = lattice.Voxel(id);
  *ci = tf.Evaluate(volume.At(v[0], v[1], v[2]));
  *g = GradientMagnitudeAtD(volume, v[0], v[1], v[2]);
}

}  // namespace

LatticeCosts EvaluateLatticeCostsCpu(const Volume& volume, const Lattice& lattice,
                                     const TransferFunction& tf, int threads) {
  const int64_t n = lattice.size();
  LatticeCosts costs = LatticeCosts::Zeros(n);
  ParallelChunks(threads, n, [&](int64_t begin, int64_t end, int) {
    for (int64_t id = begin; id < end; ++id) {
      CellCosts(volume, lattice, tf, id, &costs.ci_cell[id], &costs.g_cell[id]);
      PointCosts(volume, lattice, tf, id, &costs.ci_point[id], &costs.g_point[id]);
    }
  });
  return costs;
}

LatticeCosts EvaluateVertexCostsCpu(const Volume& volume, const Lattice& lattice,
                                    const TransferFunction& tf, std::span<const int64_t> ids) {
  LatticeCosts costs = LatticeCosts::Zeros(ids.size());
  for (size_t n = 0; n < ids.size(); ++n) {
    CellCosts(volume, lattice, tf, ids[n], &costs.ci_cell[n], &costs.g_cell[n]);
    PointCosts(volume, lattice, tf, ids[n], &costs.ci_point[n], &costs.g_point[n]);
  }
  return costs;
}

std::vector<double> NormalizeGradientCost(const std::vector<double>& g) {
  const double max_g = g.empty() ? 0.0 : *std::max_element(g.begin(), g.end());
  std::vector<double> cg(g.size(), 0.0);
  if (max_g > 0.0) {
    for (size_t n = 0; n < g.size(); ++n) cg[n] = g[n] / max_g;
  }
  return cg;
}

}  // namespace vpm

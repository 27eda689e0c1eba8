#include "server/mesh/decimate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "server/mesh/indexed_min_heap.h"
#include "server/mesh/point_grid.h"

namespace vpm {

const char* DensityModeName(DensityMode m) {
  return m == DensityMode::kSpread ? "spread" : "paper";
}

Result<DensityMode> ParseDensityMode(std::string_view name) {
  if (name == "spread") return DensityMode::kSpread;
  if (name == "paper") return DensityMode::kPaper;
  return absl::InvalidArgumentError(StrCat("density mode '", name, "': use spread or paper"));
}

namespace {

Status Validate(const DecimationInput& in, const DecimationParams& p) {
  const size_t n = in.positions.size();
  if (in.ci.size() != n || in.cg.size() != n) {
    return absl::InvalidArgumentError("decimation input arrays differ in length");
  }
  if (p.target < kAnchorCount || p.target > static_cast<int64_t>(n) + kAnchorCount) {
    return absl::InvalidArgumentError(StrCat("target ", p.target, " must be in ", kAnchorCount,
                                             "..", n + kAnchorCount,
                                             " (lattice vertices plus 8 anchors)"));
  }
  if (!(p.radius_mm > 0.0) || !std::isfinite(p.radius_mm)) {
    return absl::InvalidArgumentError(StrCat("density radius ", p.radius_mm, " mm must be > 0"));
  }
  for (double w : {p.wg, p.wd}) {
    if (!std::isfinite(w) || w < 0.0) {
      return absl::InvalidArgumentError("weights wg and wd must be finite and >= 0");
    }
  }
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(in.ci[i]) || !std::isfinite(in.cg[i])) {
      return absl::InvalidArgumentError(StrCat("vertex ", i, " has a non-finite cost"));
    }
  }
  return absl::OkStatus();
}

// Evaluates Ctotal from one vertex's terms.
struct CostModel {
  const DecimationInput& in;
  const DecimationParams& p;
  double d0;
  double operator()(int64_t v, double dens) const {
    const double cd = d0 > 0.0 ? dens / d0 : 0.0;
    const double s = p.density_mode == DensityMode::kSpread ? 1.0 - cd : cd;
    return in.ci[v] * (p.wg * in.cg[v] + p.wd * s);
  }
};

DecimationResult Finish(const std::vector<char>& alive, const std::vector<double>& dens,
                        const CostModel& cost, std::vector<int64_t> removal_order) {
  DecimationResult r;
  for (int64_t v = 0; v < static_cast<int64_t>(alive.size()); ++v) {
    if (!alive[v]) continue;
    r.kept.push_back(v);
    r.kept_cost.push_back(cost(v, dens[v]));
  }
  r.removal_order = std::move(removal_order);
  r.d0 = cost.d0;
  return r;
}

}  // namespace

Result<DecimationResult> DecimateFast(const DecimationInput& in, const DecimationParams& p) {
  RETURN_IF_ERROR(Validate(in, p));
  const int64_t n = static_cast<int64_t>(in.positions.size());
  const double r = p.radius_mm;
  const PointGrid grid(in.positions, r);
  std::vector<double> dens(n, 0.0);
  std::vector<int64_t> neighbours;
  for (int64_t v = 0; v < n; ++v) {
    neighbours.clear();
    grid.ForEachCandidate(in.positions[v], [&](int64_t u) { neighbours.push_back(u); });
    std::sort(neighbours.begin(), neighbours.end());  // sum in increasing id, as the naive scan
    for (int64_t u : neighbours) {
      const double d = PointDistance(in.positions[u], in.positions[v]);
      if (u != v && d < r) dens[v] += 1.0 / d;
    }
  }
  const double d0 = n > 0 ? *std::max_element(dens.begin(), dens.end()) : 0.0;
  const CostModel cost{in, p, d0};
  std::vector<double> initial(n);
  for (int64_t v = 0; v < n; ++v) initial[v] = cost(v, dens[v]);
  IndexedMinHeap heap(std::move(initial));
  std::vector<char> alive(n, 1);
  std::vector<int64_t> order;
  order.reserve(std::max<int64_t>(0, n - (p.target - kAnchorCount)));
  while (heap.size() > p.target - kAnchorCount) {
    const int64_t v = heap.Pop();
    alive[v] = 0;
    order.push_back(v);
    grid.ForEachCandidate(in.positions[v], [&](int64_t u) {
      if (!alive[u]) return;
      const double d = PointDistance(in.positions[u], in.positions[v]);
      if (d < r) {
        dens[u] -= 1.0 / d;
        heap.Update(u, cost(u, dens[u]));
      }
    });
  }
  return Finish(alive, dens, cost, std::move(order));
}

Result<DecimationResult> DecimateNaive(const DecimationInput& in, const DecimationParams& p) {
  RETURN_IF_ERROR(Validate(in, p));
  const int64_t n = static_cast<int64_t>(in.positions.size());
  const double r = p.radius_mm;
  std::vector<double> dens(n, 0.0);
  for (int64_t v = 0; v < n; ++v) {
    for (int64_t u = 0; u < n; ++u) {
      const double d = PointDistance(in.positions[u], in.positions[v]);
      if (u != v && d < r) dens[v] += 1.0 / d;
    }
  }
  const double d0 = n > 0 ? *std::max_element(dens.begin(), dens.end()) : 0.0;
  const CostModel cost{in, p, d0};
  std::vector<double> total(n);
  for (int64_t v = 0; v < n; ++v) total[v] = cost(v, dens[v]);
  std::vector<char> alive(n, 1);
  std::vector<int64_t> order;
  for (int64_t remaining = n; remaining > p.target - kAnchorCount; --remaining) {
    int64_t best = -1;
    for (int64_t v = 0; v < n; ++v) {
      if (alive[v] && (best < 0 || total[v] < total[best])) best = v;  // ties: smaller id
    }
    alive[best] = 0;
    order.push_back(best);
    for (int64_t u = 0; u < n; ++u) {
      if (!alive[u]) continue;
      const double d = PointDistance(in.positions[u], in.positions[best]);
      if (d < r) {
        dens[u] -= 1.0 / d;
        total[u] = cost(u, dens[u]);
      }
    }
  }
  return Finish(alive, dens, cost, std::move(order));
}

}  // namespace vpm

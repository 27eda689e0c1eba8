#include "server/mesh/decimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

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
  if (n > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    return absl::ResourceExhaustedError(StrCat("decimation of ", n, " vertices: at most 2^31"));
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

// Every vertex's neighbours within R (CSR, ids ascending), found once with a
// uniform grid of cell size R, so that each removal visits only its dozens of
// neighbours instead of the hundreds of grid candidates.
struct NeighbourLists {
  std::vector<int64_t> start;  // #N+1
  std::vector<int32_t> ids;
};

// Fills dens (#N, 1/mm) with the initial densities, each summed in
// increasing neighbour id as the naive scan does, on two threads over halves
// of the id range.
NeighbourLists FindNeighbours(const std::vector<glm::dvec3>& positions, double r,
                              std::vector<double>& dens) {
  const int64_t n = static_cast<int64_t>(positions.size());
  const PointGrid grid(positions, r);
  constexpr int kThreads = 2;
  std::vector<int64_t> counts(n, 0);
  std::vector<std::vector<int32_t>> part_ids(kThreads);
  auto work = [&](int t) {
    std::vector<std::pair<int64_t, double>> found;  // (id, distance) within R
    for (int64_t v = n * t / kThreads; v < n * (t + 1) / kThreads; ++v) {
      found.clear();
      grid.ForEachCandidate(positions[v], [&](int64_t u, const glm::dvec3& pu) {
        const double d = PointDistance(pu, positions[v]);
        if (u != v && d < r) found.emplace_back(u, d);
      });
      std::sort(found.begin(), found.end());
      for (const auto& [u, d] : found) {
        dens[v] += 1.0 / d;
        part_ids[t].push_back(static_cast<int32_t>(u));
      }
      counts[v] = static_cast<int64_t>(found.size());
    }
  };
  std::thread helper(work, 1);
  work(0);
  helper.join();
  NeighbourLists lists;
  lists.start.assign(n + 1, 0);
  for (int64_t v = 0; v < n; ++v) lists.start[v + 1] = lists.start[v] + counts[v];
  lists.ids.reserve(lists.start[n]);
  for (const auto& part : part_ids) lists.ids.insert(lists.ids.end(), part.begin(), part.end());
  return lists;
}

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
  std::vector<double> dens(n, 0.0);
  const NeighbourLists neighbours = FindNeighbours(in.positions, r, dens);
  const double d0 = n > 0 ? *std::max_element(dens.begin(), dens.end()) : 0.0;
  const CostModel cost{in, p, d0};
  std::vector<double> initial(n);
  for (int64_t v = 0; v < n; ++v) initial[v] = cost(v, dens[v]);
  IndexedMinHeap heap(std::move(initial));
  // Position, density and liveness of a vertex side by side: a removal
  // touches dozens of neighbours scattered through memory, and one cache
  // line per neighbour beats three.
  struct State {
    glm::dvec3 p;
    double dens;
    bool alive;
  };
  std::vector<State> state(n);
  for (int64_t v = 0; v < n; ++v) state[v] = {in.positions[v], dens[v], true};
  std::vector<int64_t> order;
  order.reserve(std::max<int64_t>(0, n - (p.target - kAnchorCount)));
  // A removal lowers its neighbours' densities. In spread mode that can only
  // raise their Ctotal (S = 1 - Cd, all factors >= 0, rounding monotonic), so
  // their heap keys are left as underestimates and refreshed lazily when they
  // reach the top: the top is the true minimum once its key is current. In
  // paper mode Ctotal can only fall, so keys are lowered at once (sift up).
  const bool lazy = p.density_mode == DensityMode::kSpread;
  while (heap.size() > p.target - kAnchorCount) {
    const int64_t v = heap.top();
    const double current = cost(v, state[v].dens);
    if (current != heap.cost(v)) {
      heap.Update(v, current);
      continue;
    }
    heap.Pop();
    state[v].alive = false;
    order.push_back(v);
    for (int64_t k = neighbours.start[v]; k < neighbours.start[v + 1]; ++k) {
      const int64_t id = neighbours.ids[k];
      State& u = state[id];
      if (!u.alive) continue;
      u.dens -= 1.0 / PointDistance(u.p, state[v].p);
      if (!lazy) heap.Update(id, cost(id, u.dens));
    }
  }
  std::vector<char> alive(n);
  for (int64_t v = 0; v < n; ++v) {
    alive[v] = state[v].alive;
    dens[v] = state[v].dens;
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

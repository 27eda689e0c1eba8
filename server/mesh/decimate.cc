#include "server/mesh/decimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <array>
#include <memory>
#include <optional>
#include <thread>

#include "server/common/huge_page_array.h"
#include "server/mesh/indexed_min_heap.h"
#include "server/mesh/monotone_min_queue.h"
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
  const double* ci;  // #N
  const double* cg;  // #N
  const DecimationParams& p;
  double d0;
  double operator()(int64_t v, double dens) const {
    const double cd = d0 > 0.0 ? dens / d0 : 0.0;
    const double s = p.density_mode == DensityMode::kSpread ? 1.0 - cd : cd;
    return ci[v] * (p.wg * cg[v] + p.wd * s);
  }
};

// Every vertex's neighbours within R (CSR, ids ascending), found once with
// a uniform grid of cell size R, so that each removal visits only its dozens
// of neighbours.
struct NeighbourLists {
  explicit NeighbourLists(int64_t n) : start(n + 1) {}
  HugePageArray<int64_t> start;                 // #N+1
  std::optional<HugePageArray<int32_t>> ids;    // start[N] neighbour ids, ascending per vertex
};

// The candidates around one grid bucket, sorted by id, as flat arrays (mm).
struct Candidates {
  std::vector<std::pair<int64_t, int64_t>> order;  // (id, grid slot)
  std::vector<int64_t> id;
  std::vector<double> x, y, z, d;

  // sorted: by id (needed where the order of a sum matters).
  void Gather(const PointGrid& grid, int64_t bucket, bool sorted) {
    order.clear();
    grid.ForEachSlotAround(bucket, [&](int64_t slot) { order.emplace_back(grid.item(slot), slot); });
    if (sorted) std::sort(order.begin(), order.end());
    const size_t m = order.size();
    id.resize(m);
    x.resize(m);
    y.resize(m);
    z.resize(m);
    d.resize(m);
    for (size_t j = 0; j < m; ++j) {
      id[j] = order[j].first;
      const glm::dvec3& p = grid.position(order[j].second);
      x[j] = p.x;
      y[j] = p.y;
      z[j] = p.z;
    }
  }
  // d[j] = PointDistance(candidate j, q), the same bits (one loop the
  // compiler vectorizes; sqrt is correctly rounded in either form).
  void DistancesTo(const glm::dvec3& q) {
    const size_t m = id.size();
    const double* __restrict px = x.data();
    const double* __restrict py = y.data();
    const double* __restrict pz = z.data();
    double* __restrict pd = d.data();
    const double qx = q.x, qy = q.y, qz = q.z;
    for (size_t j = 0; j < m; ++j) {
      const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
      pd[j] = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  }
};

// Fills dens (#N, 1/mm) with the initial densities, each summed in
// increasing neighbour id as the naive scan does. Bucket by bucket, the
// candidates of a bucket's 3x3x3 neighbourhood are gathered and sorted once
// for all of its points; two passes (count, then fill the exact CSR) on two
// threads over halves of the buckets.
NeighbourLists FindNeighbours(const std::vector<glm::dvec3>& positions, double r,
                              double* dens) {
  const int64_t n = static_cast<int64_t>(positions.size());
  const PointGrid grid(positions, r);
  const int64_t buckets = grid.bucket_count();
  int64_t split = 0;  // first bucket of the second thread: about n/2 points each
  while (split < buckets && grid.slot_begin(split) < n / 2) ++split;
  NeighbourLists lists(n);
  auto pass = [&](int64_t first, int64_t last, bool fill) {
    Candidates c;
    for (int64_t b = first; b < last; ++b) {
      if (grid.slot_begin(b) == grid.slot_begin(b + 1)) continue;
      c.Gather(grid, b, fill);
      const size_t m = c.id.size();
      for (int64_t q = grid.slot_begin(b); q < grid.slot_begin(b + 1); ++q) {
        const int64_t v = grid.item(q);
        c.DistancesTo(grid.position(q));
        if (!fill) {
          int64_t count = 0;
          for (size_t j = 0; j < m; ++j) count += (c.id[j] != v && c.d[j] < r) ? 1 : 0;
          lists.start[v + 1] = count;
          continue;
        }
        int64_t k = lists.start[v];
        double sum = 0.0;
        for (size_t j = 0; j < m; ++j) {
          if (c.id[j] == v || !(c.d[j] < r)) continue;
          const double inv = 1.0 / c.d[j];
          sum += inv;
          (*lists.ids)[k] = static_cast<int32_t>(c.id[j]);
          ++k;
        }
        dens[v] = sum;
      }
    }
  };
  auto both = [&](bool fill) {
    std::thread helper(pass, split, buckets, fill);
    pass(0, split, fill);
    helper.join();
  };
  both(false);
  for (int64_t v = 0; v < n; ++v) lists.start[v + 1] += lists.start[v];
  // Left uninitialized: the second pass writes every entry.
  lists.ids.emplace(lists.start[n], HugePageArray<int32_t>::Init::kNone);
  both(true);
  return lists;
}

// alive, dens: #N.
DecimationResult Finish(const char* alive, const double* dens, int64_t n, const CostModel& cost,
                        std::vector<int64_t> removal_order) {
  DecimationResult r;
  for (int64_t v = 0; v < n; ++v) {
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
  // What the removal loop reads at scattered addresses, in huge pages.
  HugePageArray<double> dens(n), ci(n, HugePageArray<double>::Init::kNone),
      cg(n, HugePageArray<double>::Init::kNone);
  HugePageArray<glm::dvec3> positions(n, HugePageArray<glm::dvec3>::Init::kNone);
  std::copy(in.ci.begin(), in.ci.end(), ci.begin());
  std::copy(in.cg.begin(), in.cg.end(), cg.begin());
  std::copy(in.positions.begin(), in.positions.end(), positions.begin());
  const NeighbourLists neighbours = FindNeighbours(in.positions, p.radius_mm, dens.data());
  const double d0 = n > 0 ? *std::max_element(dens.begin(), dens.end()) : 0.0;
  const CostModel cost{ci.data(), cg.data(), p, d0};
  const int64_t keep = p.target - kAnchorCount;
  std::vector<int64_t> order;
  order.reserve(std::max<int64_t>(0, n - keep));
  HugePageArray<char> alive(n);
  std::fill(alive.begin(), alive.end(), char{1});
  // Removes v: lowers its neighbours' densities, the removed ones' too (never
  // read again, which spares a liveness test per neighbour). Each 1/d has the
  // bits the initial sum added (PointDistance is symmetric), so a density is
  // exactly the sum over its alive neighbours taken in removal order, as in
  // the naive scan.
  auto remove = [&](int64_t v, auto&& on_neighbour) {
    alive[v] = 0;
    order.push_back(v);
    const glm::dvec3 pv = positions[v];
    const int32_t* ids = neighbours.ids->data();
    for (int64_t k = neighbours.start[v]; k < neighbours.start[v + 1]; ++k) {
      const int32_t id = ids[k];
      dens[id] -= 1.0 / PointDistance(positions[id], pv);
      on_neighbour(id);
    }
  };
  if (p.density_mode == DensityMode::kSpread) {
    // A removal can only raise its neighbours' Ctotal (S = 1 - Cd, all
    // factors >= 0, rounding monotonic), so their queued keys are left as
    // underestimates and refreshed when they come out first: the first key
    // is the true minimum once it is current. Every key queued is then at
    // least the last one taken, which a monotone queue exploits.
    MonotoneMinQueue queue;
    for (int64_t v = 0; v < n; ++v) queue.Push(cost(v, dens[v]), static_cast<int32_t>(v));
    for (int64_t remaining = n; remaining > keep;) {
      const MonotoneMinQueue::Entry top = queue.Top();
      queue.Pop();
      const double current = cost(top.item, dens[top.item]);
      if (current != top.cost) {
        queue.Push(current, top.item);
        continue;
      }
      remove(top.item, [](int32_t) {});
      --remaining;
    }
  } else {
    // In paper mode Ctotal can only fall, so keys are lowered at once.
    std::vector<double> initial(n);
    for (int64_t v = 0; v < n; ++v) initial[v] = cost(v, dens[v]);
    IndexedMinHeap heap(initial);
    while (heap.size() > keep) {
      const int64_t v = heap.top();
      heap.Pop();
      remove(v, [&](int32_t id) {
        if (heap.contains(id)) heap.Update(id, cost(id, dens[id]));
      });
    }
  }
  return Finish(alive.data(), dens.data(), n, cost, std::move(order));
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
  const CostModel cost{in.ci.data(), in.cg.data(), p, d0};
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
  return Finish(alive.data(), dens.data(), n, cost, std::move(order));
}

}  // namespace vpm

#include "server/mesh/decimate.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <array>
#include <memory>
#include <optional>
#include <atomic>
#include <thread>

#include "server/common/huge_pages.h"
#include "server/mesh/indexed_min_heap.h"
#include "server/mesh/lookahead_min_queue.h"
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
  if (p.threads < 0 || p.threads > 256) {
    return absl::InvalidArgumentError(StrCat("decimation threads ", p.threads, ": use 0..256"));
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

// Evaluates Ctotal from one vertex's terms: ci * (wg * cg + wd * S), with
// wg * cg passed in as one product (the same rounding as computing it here).
struct CostModel {
  const DecimationParams& p;
  double d0;
  double operator()(double ci, double wg_cg, double dens) const {
    const double cd = d0 > 0.0 ? dens / d0 : 0.0;
    const double s = p.density_mode == DensityMode::kSpread ? 1.0 - cd : cd;
    return ci * (wg_cg + p.wd * s);
  }
};

// One lattice vertex as DecimateFast's removal loop sees it, 64 bytes: one
// cache line in a line-aligned array (HugePageArray's large ones are). A
// removal reads a neighbour's position, density and cost terms at one
// scattered address instead of four.
struct VertexState {
  double dens;           // 1/mm, summed over the alive neighbours
  double ci;             // intensity cost
  double wg_cg;          // wg * Cg
  glm::dvec3 position;   // mm
  int64_t list_begin;    // this vertex's neighbours: ids[list_begin, +list_size)
  int32_t list_size;
  int32_t alive;         // 1 until removed
};
static_assert(sizeof(VertexState) == 64);

// The bounding box of a grid bucket's points (mm) and the test that keeps a
// candidate only if it may lie within r of one of them.
struct BucketBox {
  glm::dvec3 lo, hi;
  bool finite;

  BucketBox(const PointGrid& grid, int64_t bucket) {
    lo = hi = grid.position(grid.slot_begin(bucket));
    for (int64_t q = grid.slot_begin(bucket) + 1; q < grid.slot_begin(bucket + 1); ++q) {
      lo = glm::min(lo, grid.position(q));
      hi = glm::max(hi, grid.position(q));
    }
    finite = std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z);
  }
  // False only if PointDistance(p, q) >= r for every q in the box: per axis
  // the gap to the box is at most |p - q| after rounding (rounding is
  // monotonic), and so are its square, the sum taken in PointDistance's order
  // and the root. Exact, no margin needed.
  bool MayReach(const glm::dvec3& p, double r) const {
    if (!finite) return true;
    const double gx = std::max({lo.x - p.x, p.x - hi.x, 0.0});
    const double gy = std::max({lo.y - p.y, p.y - hi.y, 0.0});
    const double gz = std::max({lo.z - p.z, p.z - hi.z, 0.0});
    return std::sqrt(gx * gx + gy * gy + gz * gz) < r;
  }
};

// How many pops ahead of the removal loop (spread mode) each prefetch level
// works: a key's cost and record, its neighbour list, its neighbours' records
// and costs. About 4 in 5 pops are stale keys, which cost little. At
// 1,000,000 vertices, distances from (8, 4, 2) to (32, 16, 6) time the same
// within the noise, and about 20% under no prefetching (docs/MESH.md).
constexpr size_t kPrefetchRecordAt = 16;
constexpr size_t kPrefetchListAt = 8;
constexpr size_t kPrefetchNeighboursAt = 4;

// The candidates around one grid bucket (those of its 3x3x3 neighbourhood
// that may lie within r of its box, about 40% on a lattice) as flat arrays,
// for the points of the bucket one after the other.
class Candidates {
 public:
  // Positions only (mm), in grid order: enough for counting.
  void GatherPositions(const PointGrid& grid, int64_t bucket, double r) {
    Clear();
    const BucketBox box(grid, bucket);
    grid.ForEachSlotAround(bucket, [&](int64_t slot) {
      if (box.MayReach(grid.position(slot), r)) Append(grid.position(slot));
    });
  }
  // Positions and ids, ascending by id (the order of the density sums).
  void GatherSortedById(const PointGrid& grid, int64_t bucket, double r) {
    order_.clear();
    const BucketBox box(grid, bucket);
    // id < 2^31 and slot < 2^31: one integer sorts as (id, slot).
    grid.ForEachSlotAround(bucket, [&](int64_t slot) {
      if (!box.MayReach(grid.position(slot), r)) return;
      order_.push_back(static_cast<uint64_t>(grid.item(slot)) << 32 | static_cast<uint64_t>(slot));
    });
    std::sort(order_.begin(), order_.end());
    Clear();
    for (const uint64_t key : order_) {
      Append(grid.position(static_cast<int64_t>(key & 0xffffffffu)));
      id_.push_back(static_cast<int32_t>(key >> 32));
    }
  }

  // How many candidates lie within r of q (|p - q| < r, PointDistance's
  // bits), q's own point included.
  int64_t CountWithin(const glm::dvec3& q, double r) const {
    const size_t m = x_.size();
    const double* __restrict px = x_.data();
    const double* __restrict py = y_.data();
    const double* __restrict pz = z_.data();
    const double qx = q.x, qy = q.y, qz = q.z;
    double count = 0.0;  // a double sum vectorizes (an integer one does not); exact below 2^53
    for (size_t j = 0; j < m; ++j) {
      const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
      count += std::sqrt(dx * dx + dy * dy + dz * dz) < r ? 1.0 : 0.0;
    }
    return static_cast<int64_t>(count);
  }

  // After GatherSortedById: writes the ids of the candidates within r of
  // point v at q, v excluded, ascending, to out; returns the sum of their
  // 1/d (1/mm) taken in that order.
  double Neighbours(int64_t v, const glm::dvec3& q, double r, int32_t* out) {
    DistancesTo(q);
    const size_t m = x_.size();
    hit_.resize(m);
    // Branch-free: one hit in eight, in patterns the predictor misses.
    size_t hits = 0;
    for (size_t j = 0; j < m; ++j) {
      hit_[hits] = static_cast<uint32_t>(j);
      hits += static_cast<size_t>(d_[j] < r) & static_cast<size_t>(id_[j] != v);
    }
    double sum = 0.0;
    for (size_t k = 0; k < hits; ++k) {
      const uint32_t j = hit_[k];
      sum += 1.0 / d_[j];
      out[k] = id_[j];
    }
    return sum;
  }

 private:
  void Clear() {
    x_.clear();
    y_.clear();
    z_.clear();
    id_.clear();
  }
  void Append(const glm::dvec3& p) {
    x_.push_back(p.x);
    y_.push_back(p.y);
    z_.push_back(p.z);
  }
  // d_[j] = PointDistance(candidate j, q), the same bits (one loop the
  // compiler vectorizes; sqrt is correctly rounded in either form).
  void DistancesTo(const glm::dvec3& q) {
    const size_t m = x_.size();
    d_.resize(m);
    const double* __restrict px = x_.data();
    const double* __restrict py = y_.data();
    const double* __restrict pz = z_.data();
    double* __restrict pd = d_.data();
    const double qx = q.x, qy = q.y, qz = q.z;
    for (size_t j = 0; j < m; ++j) {
      const double dx = px[j] - qx, dy = py[j] - qy, dz = pz[j] - qz;
      pd[j] = std::sqrt(dx * dx + dy * dy + dz * dz);
    }
  }

  std::vector<uint64_t> order_;  // (id << 32 | grid slot), ascending
  std::vector<double> x_, y_, z_, d_;  // mm
  std::vector<int32_t> id_;
  std::vector<uint32_t> hit_;
};

// The first bucket whose slots start at or after `slot` (buckets are laid out
// in slot order).
int64_t FirstBucketFrom(const PointGrid& grid, int64_t slot) {
  int64_t lo = 0, hi = grid.bucket_count();
  while (lo < hi) {
    const int64_t mid = lo + (hi - lo) / 2;
    if (grid.slot_begin(mid) < slot) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

// Returns every vertex's neighbour ids within r (ascending per vertex) and
// sets state[v] (#N) .dens (1/mm), .list_begin and .list_size; each density
// is summed in increasing neighbour id as the naive scan does. Bucket by
// bucket, the candidates of a bucket's 3x3x3 neighbourhood that may reach its
// box are gathered and sorted once for all of its points; two passes (count, then fill the exact
// CSR). Each pass splits the buckets between `threads` threads, about the
// same number of points each; a vertex's list and density do not depend on
// which thread computes them. `cancel` is polled every 64 buckets by each
// thread; once it cancels, every thread stops and its status is returned.
Result<HugePageArray<int32_t>> FindNeighbours(const std::vector<glm::dvec3>& positions, double r,
                                              int threads, VertexState* state,
                                              const CancelToken& cancel) {
  const int64_t n = static_cast<int64_t>(positions.size());
  const PointGrid grid(positions, r);
  const int parts = static_cast<int>(
      std::clamp<int64_t>(n / kMinPointsPerSearchThread, 1, std::max(threads, 1)));
  std::vector<int64_t> part_begin(parts + 1);  // buckets of part k: [part_begin[k], part_begin[k+1])
  for (int k = 0; k <= parts; ++k) part_begin[k] = FirstBucketFrom(grid, n * k / parts);
  part_begin[parts] = grid.bucket_count();
  std::optional<HugePageArray<int32_t>> ids;
  std::atomic<bool> stop{false};
  auto pass = [&](int part, bool fill) {
    Candidates c;
    for (int64_t b = part_begin[part]; b < part_begin[part + 1]; ++b) {
      if ((b - part_begin[part]) % 64 == 0 && cancel.can_cancel()) {
        if (stop.load(std::memory_order_relaxed) || !cancel.Check().ok()) {
          stop = true;
          return;
        }
      }
      if (grid.slot_begin(b) == grid.slot_begin(b + 1)) continue;
      if (fill) {
        c.GatherSortedById(grid, b, r);
      } else {
        c.GatherPositions(grid, b, r);
      }
      for (int64_t q = grid.slot_begin(b); q < grid.slot_begin(b + 1); ++q) {
        const int64_t v = grid.item(q);
        const glm::dvec3& pq = grid.position(q);
        VertexState& sv = state[v];
        if (fill) {
          sv.dens = c.Neighbours(v, pq, r, ids->data() + sv.list_begin);
        } else {
          // v is among its own candidates, at distance PointDistance(pq, pq).
          const int64_t self = PointDistance(pq, pq) < r ? 1 : 0;
          sv.list_size = static_cast<int32_t>(c.CountWithin(pq, r) - self);
        }
      }
    }
  };
  auto all_parts = [&](bool fill) {
    std::vector<std::thread> helpers;
    for (int k = 1; k < parts; ++k) helpers.emplace_back(pass, k, fill);
    pass(0, fill);
    for (std::thread& t : helpers) t.join();
  };
  all_parts(false);
  RETURN_IF_ERROR(cancel.Check());
  int64_t total = 0;
  for (int64_t v = 0; v < n; ++v) {
    state[v].list_begin = total;
    total += state[v].list_size;
  }
  // Left uninitialized: the second pass writes every entry.
  ids.emplace(total, HugePageArray<int32_t>::Init::kNone);
  all_parts(true);
  RETURN_IF_ERROR(cancel.Check());
  return std::move(*ids);
}

// Lists the kept vertices (alive(v) true) with their costs; d0 and the
// removal order are passed through.
template <typename Alive, typename Cost>
DecimationResult Finish(int64_t n, Alive&& alive, Cost&& cost, double d0,
                        std::vector<int64_t> removal_order) {
  DecimationResult r;
  for (int64_t v = 0; v < n; ++v) {
    if (!alive(v)) continue;
    r.kept.push_back(v);
    r.kept_cost.push_back(cost(v));
  }
  r.removal_order = std::move(removal_order);
  r.d0 = d0;
  return r;
}

int DefaultThreads() {
  return static_cast<int>(std::clamp<unsigned>(std::thread::hardware_concurrency(), 1, 8));
}

}  // namespace

namespace {

// DecimateFast's state: the vertices (in huge pages, read at scattered
// addresses by the removal loop), their neighbour lists, the cost model and
// the removal order.
class FastDecimation {
 public:
  FastDecimation(const DecimationInput& in, const DecimationParams& p)
      : p_(p),
        n_(static_cast<int64_t>(in.positions.size())),
        state_(n_, HugePageArray<VertexState>::Init::kNone) {
    for (int64_t v = 0; v < n_; ++v) {
      state_[v] = VertexState{.dens = 0.0,
                              .ci = in.ci[v],
                              .wg_cg = p.wg * in.cg[v],
                              .position = in.positions[v],
                              .list_begin = 0,
                              .list_size = 0,
                              .alive = 1};
    }
  }

  // Densities from the neighbour lists, then the removals down to p.target.
  Result<DecimationResult> Run(const DecimationInput& in, const CancelToken& cancel) {
    ASSIGN_OR_RETURN(
        HugePageArray<int32_t> ids,
        FindNeighbours(in.positions, p_.radius_mm, p_.threads > 0 ? p_.threads : DefaultThreads(),
                       state_.data(), cancel));
    neighbour_ids_.emplace(std::move(ids));
    for (int64_t v = 0; v < n_; ++v) d0_ = std::max(d0_, state_[v].dens);
    cost_model_.emplace(CostModel{p_, d0_});
    const int64_t keep = p_.target - kAnchorCount;
    order_.reserve(std::max<int64_t>(0, n_ - keep));
    CancelCheckpoint checkpoint(cancel);
    RETURN_IF_ERROR(p_.density_mode == DensityMode::kSpread ? RemoveSpread(keep, checkpoint)
                                                            : RemovePaper(keep, checkpoint));
    return Finish(
        n_, [&](int64_t v) { return state_[v].alive != 0; }, [&](int64_t v) { return Cost(v); },
        d0_, std::move(order_));
  }

 private:
  double Cost(int64_t v) const {
    const VertexState& s = state_[v];
    return (*cost_model_)(s.ci, s.wg_cg, s.dens);
  }

  // Removes v: lowers its neighbours' densities, the removed ones' too (never
  // read again, which spares a liveness test per neighbour). Each 1/d has the
  // bits the initial sum added (PointDistance is symmetric), so a density is
  // exactly the sum over its alive neighbours taken in removal order, as in
  // the naive scan.
  template <typename OnNeighbour>
  void Remove(int64_t v, OnNeighbour&& on_neighbour) {
    VertexState& sv = state_[v];
    sv.alive = 0;
    order_.push_back(v);
    const glm::dvec3 pv = sv.position;
    const int32_t* ids = neighbour_ids_->data() + sv.list_begin;
    const int32_t size = sv.list_size;
    for (int32_t k = 0; k < size; ++k) {
      const int32_t id = ids[k];
      VertexState& su = state_[id];
      su.dens -= 1.0 / PointDistance(su.position, pv);
      on_neighbour(id);
    }
  }

  // Spread mode: a removal can only raise its neighbours' Ctotal (S = 1 -
  // Cd, all factors >= 0, rounding monotonic), so their queued keys are left
  // as underestimates and refreshed when they come out first: the first key
  // is the true minimum once it is current. Every key queued is then at
  // least the last one taken, which a monotone queue exploits. A removal
  // recomputes its neighbours' Ctotal while their lines are in cache, into
  // a dense array (#N, 8 MB at 1,000,000) that a stale key is checked
  // against, so that the 4 stale keys per removal cost no visit to the
  // vertex states.
  Status RemoveSpread(int64_t keep, CancelCheckpoint& checkpoint) {
    current_.emplace(n_, HugePageArray<double>::Init::kNone);
    HugePageArray<double>& current = *current_;
    for (int64_t v = 0; v < n_; ++v) {
      current[v] = Cost(v);
      queue_.Push(current[v], static_cast<int32_t>(v));
    }
    for (int64_t remaining = n_; remaining > keep;) {
      RETURN_IF_ERROR(checkpoint.Tick());
      PrefetchAhead();
      const LookaheadMinQueue::Entry top = queue_.Top();
      queue_.Pop();
      if (current[top.item] != top.cost) {
        queue_.Push(current[top.item], top.item);
        continue;
      }
      Remove(top.item, [&](int32_t id) { current[id] = Cost(id); });
      --remaining;
    }
    return absl::OkStatus();
  }

  // The loop waits on memory, not arithmetic: it prefetches, for the keys
  // a few pops ahead, what their removals will read, one level per
  // distance (the key's cost and record, then its list, then the records of
  // its neighbours), and only for keys that look current (a stale key's
  // pop reads nothing but its cost). Hints only: they change no result.
  bool LooksCurrent(const LookaheadMinQueue::Entry* e) const {
    return e != nullptr && (*current_)[e->item] == e->cost;
  }
  void PrefetchAhead() {
    if (const auto* e = queue_.Ahead(kPrefetchRecordAt)) {
      __builtin_prefetch(&(*current_)[e->item]);
      __builtin_prefetch(&state_[e->item]);
    }
    if (const auto* e = queue_.Ahead(kPrefetchListAt); LooksCurrent(e)) {
      const VertexState& se = state_[e->item];
      const int32_t* ids = neighbour_ids_->data() + se.list_begin;
      __builtin_prefetch(ids);
      if (se.list_size > 0) __builtin_prefetch(ids + se.list_size - 1);
    }
    if (const auto* e = queue_.Ahead(kPrefetchNeighboursAt); LooksCurrent(e)) {
      const VertexState& se = state_[e->item];
      const int32_t* ids = neighbour_ids_->data() + se.list_begin;
      for (int32_t k = 0; k < se.list_size; ++k) {
        __builtin_prefetch(&state_[ids[k]], 1);
        __builtin_prefetch(&(*current_)[ids[k]], 1);
      }
    }
  }

  // Paper mode: Ctotal can only fall, so keys are lowered at once.
  Status RemovePaper(int64_t keep, CancelCheckpoint& checkpoint) {
    std::vector<double> initial(n_);
    for (int64_t v = 0; v < n_; ++v) initial[v] = Cost(v);
    IndexedMinHeap heap(initial);
    while (heap.size() > keep) {
      RETURN_IF_ERROR(checkpoint.Tick());
      const int64_t v = heap.top();
      heap.Pop();
      Remove(v, [&](int32_t id) {
        if (heap.contains(id)) heap.Update(id, Cost(id));
      });
    }
    return absl::OkStatus();
  }

  const DecimationParams& p_;
  const int64_t n_;
  HugePageArray<VertexState> state_;
  std::optional<HugePageArray<int32_t>> neighbour_ids_;  // FindNeighbours' lists
  double d0_ = 0.0;
  std::optional<CostModel> cost_model_;  // once d0_ is known
  std::vector<int64_t> order_;
  std::optional<HugePageArray<double>> current_;  // spread mode: each vertex's Ctotal now
  LookaheadMinQueue queue_;
};

}  // namespace

Result<DecimationResult> DecimateFast(const DecimationInput& in, const DecimationParams& p,
                                      const CancelToken& cancel) {
  RETURN_IF_ERROR(Validate(in, p));
  RETURN_IF_ERROR(cancel.Check());
  return FastDecimation(in, p).Run(in, cancel);
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
  const CostModel cost_model{p, d0};
  auto cost = [&](int64_t v) { return cost_model(in.ci[v], p.wg * in.cg[v], dens[v]); };
  std::vector<double> total(n);
  for (int64_t v = 0; v < n; ++v) total[v] = cost(v);
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
        total[u] = cost(u);
      }
    }
  }
  return Finish(n, [&](int64_t v) { return alive[v] != 0; }, cost, d0, std::move(order));
}

}  // namespace vpm

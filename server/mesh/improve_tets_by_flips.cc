#include "server/mesh/improve_tets_by_flips.h"

#include <algorithm>
#include <functional>
#include <limits>
#include <numbers>
#include <cmath>
#include <unordered_map>

#include "server/mesh/tet_quality.h"

namespace vpm {
namespace {

using Tet = std::array<int32_t, 4>;
using TriKey = std::array<int32_t, 3>;  // sorted vertex indices

// A flip must raise the smallest angle by more than this (degrees), so that
// round-off cannot make two triangulations flip back and forth.
constexpr double kMinGainDeg = 1e-9;

struct TriKeyHash {
  size_t operator()(const TriKey& f) const {
    uint64_t h = 1469598103934665603ull;
    for (int32_t v : f) h = (h ^ static_cast<uint32_t>(v)) * 1099511628211ull;
    return static_cast<size_t>(h);
  }
};

TriKey SortedFace(int32_t a, int32_t b, int32_t c) {
  TriKey f{a, b, c};
  std::sort(f.begin(), f.end());
  return f;
}

// The smallest dihedral angle (degrees) of the tet p, or -1 unless its
// signed volume is positive. The face normals come from the vertex order, not
// from a side test against the opposite vertex, so a tet flat to round-off
// gets 0, never 180.
double OrientedMinDihedralDeg(const std::array<glm::dvec3, 4>& p) {
  if (!(SignedVolume(p[0], p[1], p[2], p[3]) > 0.0)) return -1.0;
  // Outward area normal of the face opposite vertex i: (i+1, i+2, i+3) is
  // clockwise seen from outside for even i.
  glm::dvec3 normal[4];
  for (int i = 0; i < 4; ++i) {
    const glm::dvec3& a = p[(i + 1) % 4];
    const glm::dvec3 n = glm::cross(p[(i + 2) % 4] - a, p[(i + 3) % 4] - a);
    const double length = glm::length(n);
    if (!(length > 0.0)) return 0.0;
    normal[i] = (i % 2 == 0 ? n : -n) / length;
  }
  double smallest = 180.0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      const double cosine = std::clamp(-glm::dot(normal[i], normal[j]), -1.0, 1.0);
      smallest = std::min(smallest, std::acos(cosine) * 180.0 / std::numbers::pi);
    }
  }
  return smallest;
}

// The tets with face adjacency, changed by flips.
class FlipMesh {
 public:
  FlipMesh(const std::vector<glm::dvec3>& positions, const std::vector<Tet>& tets)
      : p_(positions) {
    for (const Tet& t : tets) Add(t);
  }

  // The smallest dihedral angle (degrees) of the tet (a, b, c, d) if its
  // signed volume is positive, else -1.
  double Quality(int32_t a, int32_t b, int32_t c, int32_t d) const {
    return OrientedMinDihedralDeg({p_[a], p_[b], p_[c], p_[d]});
  }

  int32_t size() const { return static_cast<int32_t>(tets_.size()); }
  bool alive(int32_t t) const { return alive_[t] != 0; }
  double quality(int32_t t) const { return quality_[t]; }

  std::vector<Tet> AliveTets() const {
    std::vector<Tet> out;
    for (int32_t t = 0; t < size(); ++t) {
      if (alive_[t]) out.push_back(tets_[t]);
    }
    return out;
  }

  // The 2-3 flip of each face of t with an interior neighbour, the first
  // that raises the smallest angle. True when t was replaced.
  bool TryFaceFlips(int32_t t) {
    for (int i = 0; i < 4; ++i) {
      const int32_t u = Across(t, i);
      if (u < 0) continue;
      const Tet& tt = tets_[t];
      const int32_t d = tt[i];
      // The face oriented so that d lies on its positive side.
      TriKey f{tt[(i + 1) % 4], tt[(i + 2) % 4], tt[(i + 3) % 4]};
      if (i % 2 == 0) std::swap(f[1], f[2]);
      int32_t e = -1;
      for (int32_t v : tets_[u]) {
        if (v != f[0] && v != f[1] && v != f[2]) e = v;
      }
      const Tet created[3] = {{f[1], f[0], d, e}, {f[2], f[1], d, e}, {f[0], f[2], d, e}};
      double after = std::numeric_limits<double>::infinity();
      for (const Tet& n : created) after = std::min(after, Quality(n[0], n[1], n[2], n[3]));
      if (!(after > std::min(quality_[t], quality_[u]) + kMinGainDeg)) continue;
      Remove(t);
      Remove(u);
      for (const Tet& n : created) Add(n);
      return true;
    }
    return false;
  }

  // Edge removal on each edge of t (the first that raises the smallest
  // angle). True when t was replaced.
  bool TryEdgeRemovals(int32_t t) {
    static constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (const auto& e : kEdges) {
      if (TryEdgeRemoval(t, e[0], e[1])) return true;
    }
    return false;
  }

 private:
  void Add(const Tet& t) {
    const int32_t id = size();
    tets_.push_back(t);
    alive_.push_back(1);
    quality_.push_back(Quality(t[0], t[1], t[2], t[3]));
    for (int i = 0; i < 4; ++i) {
      auto [it, inserted] = faces_.try_emplace(FaceOpposite(t, i), std::array<int32_t, 2>{-1, -1});
      (it->second[0] < 0 ? it->second[0] : it->second[1]) = id;
    }
  }

  void Remove(int32_t id) {
    alive_[id] = 0;
    for (int i = 0; i < 4; ++i) {
      auto it = faces_.find(FaceOpposite(tets_[id], i));
      auto& slots = it->second;
      if (slots[0] == id) slots[0] = slots[1];
      slots[1] = -1;
      if (slots[0] < 0) faces_.erase(it);
    }
  }

  static TriKey FaceOpposite(const Tet& t, int i) {
    return SortedFace(t[(i + 1) % 4], t[(i + 2) % 4], t[(i + 3) % 4]);
  }

  // The tet across the face of t opposite its vertex i, -1 on the hull.
  int32_t Across(int32_t t, int i) const {
    const auto& slots = faces_.at(FaceOpposite(tets_[t], i));
    return slots[0] == t ? slots[1] : slots[0];
  }

  static int IndexOf(const Tet& t, int32_t v) {
    return static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
  }

  // The ring around the edge (t[ia], t[ib]): vertices r_0..r_{n-1} with
  // every ring tet (a, b, r_k, r_k+1) positively oriented, and the tets.
  // False for an edge on the hull or a ring longer than kMaxEdgeRemovalRing.
  bool Ring(int32_t t, int ia, int ib, std::vector<int32_t>& ring,
            std::vector<int32_t>& ring_tets) const {
    const Tet& tt = tets_[t];
    std::array<int, 4> order{ia, ib, 0, 0};
    int k = 2;
    for (int i = 0; i < 4; ++i) {
      if (i != ia && i != ib) order[k++] = i;
    }
    // (a, b, c, d) is an even permutation of t, hence positive, or swap c, d.
    int inversions = 0;
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) inversions += order[i] > order[j];
    }
    if (inversions % 2 == 1) std::swap(order[2], order[3]);
    ring = {tt[order[2]], tt[order[3]]};
    ring_tets = {t};
    int32_t cur = t, prev = ring[0], last = ring[1];
    for (;;) {
      const int32_t next = Across(cur, IndexOf(tets_[cur], prev));
      if (next < 0) return false;
      if (next == t) break;
      if (static_cast<int>(ring_tets.size()) >= kMaxEdgeRemovalRing) return false;
      int32_t apex = -1;
      for (int32_t v : tets_[next]) {
        if (v != tt[ia] && v != tt[ib] && v != last) apex = v;
      }
      ring_tets.push_back(next);
      ring.push_back(apex);
      prev = last;
      last = apex;
      cur = next;
    }
    // The walk came back through r_0: it was pushed again last.
    if (ring.back() != ring.front()) return false;
    ring.pop_back();
    return ring.size() == ring_tets.size() && ring.size() >= 3;
  }

  bool TryEdgeRemoval(int32_t t, int ia, int ib) {
    std::vector<int32_t> ring, ring_tets;
    if (!Ring(t, ia, ib, ring, ring_tets)) return false;
    const int32_t a = tets_[t][ia], b = tets_[t][ib];
    double before = std::numeric_limits<double>::infinity();
    for (int32_t r : ring_tets) before = std::min(before, quality_[r]);
    // best[i][j]: the largest smallest angle over triangulations of the ring
    // polygon r_i..r_j, each triangle (r_i, r_k, r_j) coned to b and to a.
    const int n = static_cast<int>(ring.size());
    constexpr double kInf = std::numeric_limits<double>::infinity();
    std::vector<double> best(n * n, kInf);
    std::vector<int> split(n * n, -1);
    for (int length = 2; length < n; ++length) {
      for (int i = 0; i + length < n; ++i) {
        const int j = i + length;
        double& cell = best[i * n + j];
        cell = -kInf;
        for (int k = i + 1; k < j; ++k) {
          const double q = std::min({best[i * n + k], best[k * n + j],
                                     Quality(ring[i], ring[k], ring[j], b),
                                     Quality(ring[i], ring[j], ring[k], a)});
          if (q > cell) {
            cell = q;
            split[i * n + j] = k;
          }
        }
      }
    }
    if (!(best[n - 1] > before + kMinGainDeg)) return false;
    for (int32_t r : ring_tets) Remove(r);
    const std::function<void(int, int)> emit = [&](int i, int j) {
      if (j - i < 2) return;
      const int k = split[i * n + j];
      Add({ring[i], ring[k], ring[j], b});
      Add({ring[i], ring[j], ring[k], a});
      emit(i, k);
      emit(k, j);
    };
    emit(0, n - 1);
    return true;
  }

  const std::vector<glm::dvec3>& p_;
  std::vector<Tet> tets_;
  std::vector<uint8_t> alive_;
  std::vector<double> quality_;
  std::unordered_map<TriKey, std::array<int32_t, 2>, TriKeyHash> faces_;
};

double SmallestQuality(const FlipMesh& mesh) {
  double smallest = std::numeric_limits<double>::infinity();
  for (int32_t t = 0; t < mesh.size(); ++t) {
    if (mesh.alive(t)) smallest = std::min(smallest, mesh.quality(t));
  }
  return smallest;
}

}  // namespace

Result<FlipStats> ImproveTetsByFlips(const std::vector<glm::dvec3>& positions,
                                     std::vector<Tet>& tets, const FlipOptions& options,
                                     const CancelToken& cancel) {
  FlipStats stats;
  if (tets.empty()) return stats;
  RETURN_IF_ERROR(cancel.Check());
  FlipMesh mesh(positions, tets);
  stats.min_dihedral_before_deg = SmallestQuality(mesh);
  CancelCheckpoint checkpoint(cancel, 256);
  for (int pass = 0; pass < options.max_passes; ++pass) {
    RETURN_IF_ERROR(cancel.Check());
    std::vector<std::pair<double, int32_t>> poor;
    for (int32_t t = 0; t < mesh.size(); ++t) {
      if (mesh.alive(t) && mesh.quality(t) < options.target_min_dihedral_deg) {
        poor.emplace_back(mesh.quality(t), t);
      }
    }
    std::sort(poor.begin(), poor.end());
    int64_t changes = 0;
    for (const auto& [quality, t] : poor) {
      RETURN_IF_ERROR(checkpoint.Tick());
      if (!mesh.alive(t)) continue;
      if (mesh.TryEdgeRemovals(t)) {
        ++stats.edge_removals;
        ++changes;
      } else if (mesh.TryFaceFlips(t)) {
        ++stats.face_flips;
        ++changes;
      }
    }
    stats.passes = pass + 1;
    if (changes == 0) break;
  }
  tets = mesh.AliveTets();
  stats.min_dihedral_after_deg = SmallestQuality(mesh);
  return stats;
}

}  // namespace vpm

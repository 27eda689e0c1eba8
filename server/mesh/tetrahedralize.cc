#include "server/mesh/tetrahedralize.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <utility>
#include <vector>

// The only CGAL includes of the project: CGAL compiles slowly.
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include "server/common/clock.h"
#include "server/mesh/improve_tets_by_flips.h"
#include "server/mesh/tet_quality.h"

namespace vpm {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using VertexBase = CGAL::Triangulation_vertex_base_with_info_3<int32_t, Kernel>;
using DataStructure =
    CGAL::Triangulation_data_structure_3<VertexBase,
                                         CGAL::Delaunay_triangulation_cell_base_3<Kernel>>;
using Delaunay = CGAL::Delaunay_triangulation_3<Kernel, DataStructure>;
using Point = Kernel::Point_3;
using Tet = std::array<int32_t, 4>;

std::string FormatPosition(const glm::dvec3& p) {
  return StrCat("(", p.x, ", ", p.y, ", ", p.z, ")");
}

Status CheckPositions(const std::vector<MeshVertex>& vertices, const glm::dvec3& extent) {
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(extent[a]) || extent[a] <= 0.0) {
      return absl::InvalidArgumentError(StrCat("Tetrahedralize: box extent ",
                                               FormatPosition(extent),
                                               " mm must be positive and finite"));
    }
  }
  if (vertices.size() < 4) {
    return absl::InvalidArgumentError(StrCat("Tetrahedralize: ", vertices.size(),
                                             " vertices; a tetrahedralization needs at least 4"));
  }
  if (vertices.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    return absl::InvalidArgumentError("Tetrahedralize: too many vertices for int32 indices");
  }
  // Vertices outside the box would make the hull larger than the box.
  const double slack = 1e-9 * std::max({extent.x, extent.y, extent.z});
  for (size_t v = 0; v < vertices.size(); ++v) {
    const glm::dvec3& p = vertices[v].position_mm;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return absl::InvalidArgumentError(
          StrCat("Tetrahedralize: vertex ", v, " has a non-finite position ", FormatPosition(p)));
    }
    for (int a = 0; a < 3; ++a) {
      if (p[a] < -slack || p[a] > extent[a] + slack) {
        return absl::InvalidArgumentError(StrCat("Tetrahedralize: vertex ", v, " at ",
                                                 FormatPosition(p), " mm lies outside the box [0, ",
                                                 FormatPosition(extent), "] mm"));
      }
    }
  }
  return absl::OkStatus();
}

Status CheckDuplicates(const std::vector<MeshVertex>& vertices) {
  std::vector<int32_t> order(vertices.size());
  std::iota(order.begin(), order.end(), 0);
  auto key = [&](int32_t v) {
    const glm::dvec3& p = vertices[v].position_mm;
    return std::make_tuple(p.x, p.y, p.z, v);
  };
  std::sort(order.begin(), order.end(), [&](int32_t a, int32_t b) { return key(a) < key(b); });
  std::string listed;
  int64_t duplicates = 0;
  for (size_t n = 1; n < order.size(); ++n) {
    const glm::dvec3& p = vertices[order[n]].position_mm;
    if (p != vertices[order[n - 1]].position_mm) continue;
    if (++duplicates <= 5) {
      listed += StrCat(duplicates > 1 ? "; " : "", "vertices ", order[n - 1], " and ", order[n],
                       " at ", FormatPosition(p));
    }
  }
  if (duplicates == 0) return absl::OkStatus();
  return absl::InvalidArgumentError(StrCat("Tetrahedralize: ", duplicates,
                                           " duplicate vertex position(s): ", listed,
                                           duplicates > 5 ? "; ..." : ""));
}

// An even permutation of `t` (orientation kept) that puts the smallest index
// first and the smallest of the other three second.
Tet CanonicalRotation(const Tet& t) {
  const int m = static_cast<int>(std::min_element(t.begin(), t.end()) - t.begin());
  // Double transpositions bring position m to the front.
  static constexpr int kFront[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
  Tet r{t[kFront[m][0]], t[kFront[m][1]], t[kFront[m][2]], t[kFront[m][3]]};
  // A 3-cycle of the last three brings their smallest to position 1.
  while (r[1] > r[2] || r[1] > r[3]) r = {r[0], r[2], r[3], r[1]};
  return r;
}

// The Delaunay triangulation of the vertices (mm), inserted in batches so
// that a cancelled call stops between two. CGAL's Delaunay triangulation
// does not depend on the insertion order (symbolic perturbation settles
// cospherical points), and the tets are sorted afterwards.
Status Triangulate(const std::vector<MeshVertex>& vertices, Delaunay& delaunay,
                   const CancelToken& cancel) {
  std::vector<std::pair<Point, int32_t>> points;
  points.reserve(vertices.size());
  for (size_t v = 0; v < vertices.size(); ++v) {
    const glm::dvec3& p = vertices[v].position_mm;
    points.emplace_back(Point(p.x, p.y, p.z), static_cast<int32_t>(v));
  }
  constexpr size_t kInsertBatch = 8192;
  for (size_t begin = 0; begin < points.size(); begin += kInsertBatch) {
    RETURN_IF_ERROR(cancel.Check());
    const size_t end = std::min(points.size(), begin + kInsertBatch);
    delaunay.insert(points.begin() + begin, points.begin() + end);
  }
  RETURN_IF_ERROR(cancel.Check());
  if (delaunay.dimension() < 3) {
    return absl::InvalidArgumentError(
        StrCat("Tetrahedralize: the ", vertices.size(),
               " vertices are coplanar; no tetrahedron can be built"));
  }
  return absl::OkStatus();
}

// The triangulation's finite cells as positively oriented tets in their
// canonical rotation; `removed` counts the flat cells dropped.
std::vector<Tet> OrientedTets(const Delaunay& delaunay, int64_t& removed) {
  std::vector<Tet> tets;
  tets.reserve(delaunay.number_of_finite_cells());
  for (auto cell = delaunay.finite_cells_begin(); cell != delaunay.finite_cells_end(); ++cell) {
    Tet t;
    for (int c = 0; c < 4; ++c) t[c] = cell->vertex(c)->info();
    // The exact predicate: a cell is dropped only if truly flat.
    const CGAL::Orientation o =
        CGAL::orientation(cell->vertex(0)->point(), cell->vertex(1)->point(),
                          cell->vertex(2)->point(), cell->vertex(3)->point());
    if (o == CGAL::COPLANAR) {
      ++removed;
      continue;
    }
    if (o == CGAL::NEGATIVE) std::swap(t[2], t[3]);
    tets.push_back(CanonicalRotation(t));
  }
  return tets;
}

// The hull must be the box: the tet volumes add up to the box volume.
Status CheckCoversTheBox(const std::vector<glm::dvec3>& positions, const std::vector<Tet>& tets,
                         const glm::dvec3& box_extent_mm) {
  double volume = 0.0;
  for (const Tet& t : tets) {
    volume += SignedVolume(positions[t[0]], positions[t[1]], positions[t[2]], positions[t[3]]);
  }
  const double box_volume = box_extent_mm.x * box_extent_mm.y * box_extent_mm.z;
  if (!(std::abs(volume - box_volume) <= 1e-9 * box_volume)) {
    return absl::InvalidArgumentError(StrCat("Tetrahedralize: the tets cover ", volume,
                                             " mm^3 but the box ", FormatPosition(box_extent_mm),
                                             " mm has ", box_volume,
                                             " mm^3; are the 8 box corners among the vertices?"));
  }
  return absl::OkStatus();
}

}  // namespace

Status Tetrahedralize(ProxyMesh& mesh, const glm::dvec3& box_extent_mm, const CancelToken& cancel) {
  const auto start = std::chrono::steady_clock::now();
  RETURN_IF_ERROR(CheckPositions(mesh.vertices, box_extent_mm));
  RETURN_IF_ERROR(CheckDuplicates(mesh.vertices));

  Delaunay delaunay;
  RETURN_IF_ERROR(Triangulate(mesh.vertices, delaunay, cancel));

  int64_t removed = 0;
  std::vector<Tet> tets = OrientedTets(delaunay, removed);
  // Sorted before the flips too, so that they see the tets in an order that
  // depends on the positions only, not on CGAL's cell order.
  std::sort(tets.begin(), tets.end());
  std::vector<glm::dvec3> points_mm(mesh.vertices.size());
  for (size_t v = 0; v < points_mm.size(); ++v) points_mm[v] = mesh.vertices[v].position_mm;
  // Delaunay keeps the slivers of cospherical lattice rows; flips remove
  // most (improve_tets_by_flips.h, docs/MESH.md "Tet quality").
  RETURN_IF_ERROR(ImproveTetsByFlips(points_mm, tets, {}, cancel).status());
  for (Tet& t : tets) t = CanonicalRotation(t);
  std::sort(tets.begin(), tets.end());

  RETURN_IF_ERROR(CheckCoversTheBox(points_mm, tets, box_extent_mm));

  mesh.tets = std::move(tets);
  mesh.quality = MeasureTetQuality(mesh);
  mesh.quality.removed_zero_volume = removed;
  mesh.stats.tets = static_cast<int64_t>(mesh.tets.size());
  mesh.stats.tetrahedralize_ms =
      MsSince(start);
  return absl::OkStatus();
}

}  // namespace vpm

#include "server/measures/compare_meshes.h"

#include <chrono>
#include <cmath>

#include "server/common/clock.h"
#include "server/mesh/boundary_vertices.h"
#include "server/mesh/tetrahedralize.h"

namespace vpm {
namespace {

// The grid with the most vertices <= budget, and among those the one closest
// to the box proportions.
std::array<int64_t, 3> RegularGrid(const VolumeGeometry& g, int64_t budget) {
  const glm::dvec3 e = glm::dvec3(g.dims[0], g.dims[1], g.dims[2]) * g.spacing_mm;
  const double scale = std::cbrt(static_cast<double>(budget) / (e.x * e.y * e.z));
  std::array<int64_t, 3> best{1, 1, 1};
  double best_shape = 1e300;
  std::array<int64_t, 3> lo, hi;
  for (int a = 0; a < 3; ++a) {
    const int64_t guess = static_cast<int64_t>(std::round(e[a] * scale));
    lo[a] = std::max<int64_t>(1, guess - 3);
    hi[a] = std::min<int64_t>(g.dims[a], guess + 3);
  }
  for (int64_t x = lo[0]; x <= hi[0]; ++x)
    for (int64_t y = lo[1]; y <= hi[1]; ++y)
      for (int64_t z = lo[2]; z <= hi[2]; ++z) {
        const int64_t n = x * y * z;
        if (n > budget) continue;
        const double shape = std::abs(std::log(e.x / x / (e.y / y))) +
                             std::abs(std::log(e.y / y / (e.z / z)));
        const int64_t best_n = best[0] * best[1] * best[2];
        if (n > best_n || (n == best_n && shape < best_shape)) {
          best = {x, y, z};
          best_shape = shape;
        }
      }
  return best;
}

Result<MeshComparisonRow> Measure(const Volume& volume, const TransferFunction& tf,
                                  std::string name, const ProxyMesh& mesh, double build_ms) {
  MeshComparisonRow row;
  row.name = std::move(name);
  row.vertices = static_cast<int64_t>(mesh.vertices.size());
  row.boundary_vertices = mesh.stats.boundary;
  row.steiner_vertices = mesh.stats.steiner;
  row.tets = static_cast<int64_t>(mesh.tets.size());
  row.quality = mesh.quality;
  row.build_ms = build_ms;
  ASSIGN_OR_RETURN(row.reconstruction, MeasureReconstructionError(volume, mesh, tf));
  ASSIGN_OR_RETURN(row.largest_empty_sphere, LargestEmptySphere(mesh, volume, tf));
  return row;
}

}  // namespace

Result<ProxyMesh> BuildRegularMesh(const Volume& volume, int64_t target) {
  if (target < kAnchorCount + 1) {
    return absl::InvalidArgumentError(StrCat("target ", target, " leaves no lattice vertex"));
  }
  ASSIGN_OR_RETURN(Lattice lattice,
                   Lattice::Create(volume.geometry(),
                                   RegularGrid(volume.geometry(), target - kAnchorCount)));
  ProxyMesh mesh;
  mesh.vertices = MakeAnchors(volume.geometry());
  for (int64_t id = 0; id < lattice.size(); ++id) {
    mesh.vertices.push_back({.position_mm = lattice.Position(id),
                             .lattice_id = id,
                             .kind = VertexKind::kLattice,
                             .voxel = lattice.Voxel(id)});
  }
  // The same box-face vertices as the built meshes, so that the rows differ
  // by their interior vertices only.
  const std::vector<MeshVertex> boundary =
      BoundaryVertices(mesh.vertices, volume.geometry(), {.min_cell_mm = 0.5 * lattice.h_mm()});
  mesh.stats.boundary = static_cast<int64_t>(boundary.size());
  mesh.vertices.insert(mesh.vertices.end(), boundary.begin(), boundary.end());
  RETURN_IF_ERROR(Tetrahedralize(mesh, volume.geometry().extent_mm()));
  return mesh;
}

Result<std::vector<MeshComparisonRow>> CompareMeshes(const Volume& volume, const MeshParams& params,
                                                     const MeshGpu& gpu) {
  ASSIGN_OR_RETURN(TransferFunction tf, TransferFunction::FromSpec(params.tf, volume));
  std::vector<MeshComparisonRow> rows;
  auto t0 = SteadyClock::now();
  ASSIGN_OR_RETURN(ProxyMesh regular, BuildRegularMesh(volume, params.target));
  ASSIGN_OR_RETURN(auto row, Measure(volume, tf, "regular", regular, MsSince(t0)));
  rows.push_back(std::move(row));
  for (Footprint footprint : {Footprint::kCell, Footprint::kPoint}) {
    for (DensityMode mode : {DensityMode::kSpread, DensityMode::kPaper}) {
      MeshParams p = params;
      p.footprint = footprint;
      p.density_mode = mode;
      p.refine_at_mm.reset();
      t0 = SteadyClock::now();
      ASSIGN_OR_RETURN(ProxyMesh mesh, BuildProxyMesh(volume, p, gpu));
      const double ms = MsSince(t0);
      ASSIGN_OR_RETURN(
          auto r, Measure(volume, tf, StrCat(FootprintName(footprint), "/", DensityModeName(mode)),
                          mesh, ms));
      r.is_default = footprint == MeshParams{}.footprint && mode == MeshParams{}.density_mode;
      rows.push_back(std::move(r));
    }
  }
  return rows;
}

}  // namespace vpm

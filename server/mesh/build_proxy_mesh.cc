#include "server/mesh/build_proxy_mesh.h"

#include <algorithm>
#include <chrono>

#include "server/common/clock.h"
#include "server/mesh/boundary_vertices.h"
#include "server/mesh/hard_reach_steiner_points.h"
#include "server/mesh/lattice_costs_rows.h"
#include "server/mesh/refine_at_point.h"
#include "server/mesh/sliver_steiner_points.h"
#include "server/mesh/tetrahedralize.h"

namespace vpm {
namespace {

Status CheckParams(const MeshParams& p) {
  for (double v : {p.wg, p.wd, p.radius_factor, p.roi_radius_factor}) {
    if (!std::isfinite(v) || v < 0.0) {
      return absl::InvalidArgumentError("wg, wd, radius factor and roi factor must be finite, >= 0");
    }
  }
  if (!(p.radius_factor > 0.0)) return absl::InvalidArgumentError("radius factor must be > 0");
  return absl::OkStatus();
}

// The tetrahedralized mesh's Steiner points: those that bring hard tissue
// within reach of the grab (with a grab point), then those that mend
// slivers; counted in mesh.stats.steiner.
Status AddSteinerPoints(const Volume& volume, const DecimatedLattice& base,
                        const MeshParams& params, const CancelToken& cancel, ProxyMesh& mesh) {
  if (params.hard_reach_factor > 0.0 && params.refine_at_mm) {
    // Before the sliver points, which then mend the tets these leave.
    const double h = base.stats.h_mm;
    const HardReachParams hp{.max_reach_mm = params.hard_reach_factor * h,
                             .center_mm = *params.refine_at_mm,
                             .radius_mm = params.hard_reach_radius_factor * h,
                             .min_spacing_mm = h / 6.0};
    ASSIGN_OR_RETURN(
        const HardReachStats reach,
        AddHardReachSteinerPoints(mesh, volume, base.stats.R_mm, params.classify, hp, cancel));
    mesh.stats.steiner += reach.added;
  }
  if (params.steiner_min_dihedral_deg > 0.0) {
    // Steiner points only where a tet stays under the target after flips;
    // h/6 apart at least, half the refinement spacing (docs/MESH.md).
    const SteinerParams sp{.target_min_dihedral_deg = params.steiner_min_dihedral_deg,
                           .min_spacing_mm = base.stats.h_mm / 6.0};
    ASSIGN_OR_RETURN(const SteinerStats steiner,
                     AddSliverSteinerPoints(mesh, volume.geometry(), sp, cancel));
    mesh.stats.steiner += steiner.added;
  }
  return absl::OkStatus();
}

}  // namespace

std::vector<MeshVertex> MakeAnchors(const VolumeGeometry& geometry) {
  std::vector<MeshVertex> anchors;
  const glm::dvec3 extent = geometry.extent_mm();
  for (int c = 0; c < 8; ++c) {
    const std::array<bool, 3> hi{(c & 1) != 0, (c & 2) != 0, (c & 4) != 0};
    MeshVertex v{.lattice_id = -1, .kind = VertexKind::kAnchor};
    for (int a = 0; a < 3; ++a) {
      v.position_mm[a] = hi[a] ? extent[a] : 0.0;
      v.voxel[a] = hi[a] ? geometry.dims[a] - 1 : 0;
    }
    anchors.push_back(v);
  }
  return anchors;
}

Result<DecimatedLattice> DecimateLattice(const Volume& volume, const MeshParams& params,
                                         const MeshGpu& gpu, const CancelToken& cancel) {
  RETURN_IF_ERROR(CheckParams(params));
  RETURN_IF_ERROR(cancel.Check());
  ASSIGN_OR_RETURN(Lattice lattice, Lattice::Create(volume.geometry(), params.grid));
  ASSIGN_OR_RETURN(TransferFunction tf, TransferFunction::FromSpec(params.tf, volume));
  auto t0 = SteadyClock::now();
  LatticeCosts costs;
  const char* evaluated_on = kStep1OnCpuReference;
  if (gpu.lattice_costs != nullptr && gpu.lattice_costs->runs_on_cpu()) {
    // Lavapipe: the same cores run native rows about 15x faster than the
    // kernels (lattice_costs_rows.h).
    ASSIGN_OR_RETURN(costs, EvaluateLatticeCostsRows(volume, lattice, tf, 0, cancel));
    evaluated_on = kStep1OnCpuRows;
  } else if (gpu.volume != nullptr && gpu.lattice_costs != nullptr) {
    ASSIGN_OR_RETURN(costs, gpu.lattice_costs->Evaluate(*gpu.volume, lattice, tf));
    evaluated_on = kStep1OnGpu;
  } else {
    costs = EvaluateLatticeCostsCpu(volume, lattice, tf);
  }
  RETURN_IF_ERROR(cancel.Check());
  MeshStats stats;
  stats.evaluate_ms = MsSince(t0);
  stats.evaluated_on = evaluated_on;
  t0 = SteadyClock::now();
  const auto& g = costs.g(params.footprint);
  DecimationInput input{.ci = costs.ci(params.footprint), .cg = NormalizeGradientCost(g)};
  input.positions.resize(lattice.size());
  for (int64_t id = 0; id < lattice.size(); ++id) input.positions[id] = lattice.Position(id);
  const double h = lattice.h_mm();
  const DecimationParams dp{.target = params.target,
                            .wg = params.wg,
                            .wd = params.wd,
                            .radius_mm = params.radius_factor * h,
                            .density_mode = params.density_mode};
  ASSIGN_OR_RETURN(DecimationResult kept, DecimateFast(input, dp, cancel));
  std::vector<MeshVertex> vertices = MakeAnchors(volume.geometry());
  for (size_t n = 0; n < kept.kept.size(); ++n) {
    const int64_t id = kept.kept[n];
    vertices.push_back({.position_mm = input.positions[id],
                        .lattice_id = id,
                        .kind = VertexKind::kLattice,
                        .voxel = lattice.Voxel(id),
                        .cost = kept.kept_cost[n]});
  }
  stats.decimate_ms = MsSince(t0);
  stats.grid = {int32_t(params.grid[0]), int32_t(params.grid[1]), int32_t(params.grid[2])};
  stats.lattice_vertices = lattice.size();
  stats.kept_lattice = static_cast<int64_t>(kept.kept.size());
  stats.anchors = kAnchorCount;
  stats.h_mm = h;
  stats.R_mm = dp.radius_mm;
  const double g_max = g.empty() ? 0.0 : *std::max_element(g.begin(), g.end());
  return DecimatedLattice{std::move(lattice), std::move(tf), std::move(costs), g_max,
                          std::move(vertices), stats};
}

Result<ProxyMesh> FinishProxyMesh(const Volume& volume, const DecimatedLattice& base,
                                  const MeshParams& params, const CancelToken& cancel) {
  RETURN_IF_ERROR(cancel.Check());
  ProxyMesh mesh;
  mesh.stats = base.stats;
  mesh.vertices = base.vertices;
  auto t0 = SteadyClock::now();
  if (params.refine_at_mm) {
    const RefineParams rp{.point_mm = *params.refine_at_mm,
                          .roi_radius_mm = params.roi_radius_factor * base.stats.h_mm,
                          .refine_count = params.refine_count,
                          .footprint = params.footprint};
    ASSIGN_OR_RETURN(auto refined,
                     RefineAtPoint(volume, base.lattice, base.tf, base.g_max, mesh.vertices, rp));
    mesh.stats.refined = static_cast<int64_t>(refined.size());
    mesh.vertices.insert(mesh.vertices.end(), refined.begin(), refined.end());
  }
  mesh.stats.refine_ms = MsSince(t0);
  RETURN_IF_ERROR(cancel.Check());
  t0 = SteadyClock::now();
  const BoundaryParams bp{.min_cell_mm = 0.5 * base.stats.h_mm};
  const std::vector<MeshVertex> boundary =
      BoundaryVertices(mesh.vertices, volume.geometry(), bp);
  mesh.stats.boundary = static_cast<int64_t>(boundary.size());
  mesh.vertices.insert(mesh.vertices.end(), boundary.begin(), boundary.end());
  mesh.stats.boundary_ms = MsSince(t0);
  t0 = SteadyClock::now();
  RETURN_IF_ERROR(Tetrahedralize(mesh, volume.geometry().extent_mm(), cancel));
  const double tetrahedralize_ms = MsSince(t0);
  t0 = SteadyClock::now();
  RETURN_IF_ERROR(AddSteinerPoints(volume, base, params, cancel, mesh));
  mesh.stats.steiner_ms = MsSince(t0);
  RETURN_IF_ERROR(cancel.Check());
  mesh.stats.tetrahedralize_ms = tetrahedralize_ms;  // the Steiner rounds' own are in steiner_ms
  t0 = SteadyClock::now();
  // Step 3 after the tetrahedralization: it reads positions only, and the
  // Steiner points need classifying like the rest.
  RETURN_IF_ERROR(ClassifyHardness(volume, base.stats.R_mm, params.classify, mesh.vertices));
  mesh.stats.hard = std::count_if(mesh.vertices.begin(), mesh.vertices.end(),
                                  [](const MeshVertex& v) { return v.hard; });
  mesh.stats.classify_ms = MsSince(t0);
  mesh.stats.tets = static_cast<int64_t>(mesh.tets.size());
  mesh.stats.total_ms = mesh.stats.evaluate_ms + mesh.stats.decimate_ms + mesh.stats.refine_ms +
                        mesh.stats.boundary_ms + mesh.stats.classify_ms +
                        mesh.stats.tetrahedralize_ms + mesh.stats.steiner_ms;
  return mesh;
}

}  // namespace vpm

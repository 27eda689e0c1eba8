// Mesh validity per volume and footprint (docs/ALGORITHM.md section 6,
// "Validity"): vertices, tets, the smallest dihedral angle, the inverted tets
// after drags of 0.5 h, 1 h and 1.5 h in the interactive FEM settings
// (SolverOptions defaults, the drag in 10 increments, as a user drags) and
// the measuring ones (MeasurementFemOptions, at once), the mesh build time
// and the mean interactive FEM step time.
//
// The mesh is the default build (20^3 lattice to 250, G at most a third of
// the voxels per axis) refined at the grab
// point, as the server does; the grab takes the vertices within h/2 and drags
// them anteriorly (-y). Grab point: the phantom's left_kidney_center (the
// standard drag), else the centre of the image box.
//
// Usage: mesh_validity_bench [--max-load-steps N] [--intermediate-newton N]
//                            [--steiner DEG] [--hard-reach F]
//                            [--hard-reach-radius F] [VOLUME [TF]]...
//   (default: phantom:abdomen?size=128)
//   --min-load-fraction F, --measuring-load-steps N: SolverOptions of both
//   settings and max_load_steps of the measuring one
//   --steiner DEG: MeshParams::steiner_min_dihedral_deg (default 5; 0: no
//   Steiner points, the mesh of flips alone)
//   --hard-reach F, --hard-reach-radius F: MeshParams::hard_reach_factor
//   and hard_reach_radius_factor (defaults 2 and 2; --hard-reach 0: no
//   Steiner points on long hard edges, the mesh before issue 16 point 3)
//   --hard-factor F: FemMaterial::hard_factor of both settings (default
//   1e4; 1 makes the tets touching bone as soft as the rest, bone vertices
//   staying fixed)
//   MESH_VALIDITY_EXPLAIN=1 prints what each inverted tet is made of
//   (bench/explain_inverted_tets.h).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "bench/explain_inverted_tets.h"
#include "server/fem/fem_model.h"
#include "server/io/read_volume.h"
#include "server/measures/deformation_measures.h"
#include "server/mesh/build_proxy_mesh.h"

using namespace vpm;

namespace {

const Volume* explain_volume = nullptr;
int measuring_load_steps = 0;  // 0: MeasurementFemOptions' own
double hard_reach = MeshParams{}.hard_reach_factor;
double hard_factor = FemMaterial{}.hard_factor;
double hard_reach_radius = MeshParams{}.hard_reach_radius_factor;

struct DragResult {
  int64_t inverted = 0;
  bool forced = false;
  double step_ms = 0.0;  // mean FEM time per drag increment
};

DragResult RunDrag(const ProxyMesh& mesh, const glm::dvec3& extent, const glm::dvec3& grab,
                   double radius, const glm::dvec3& drag, const FemOptions& options,
                   int increments) {
  FemModel model = bench::Check(FemModel::Create(mesh, extent, options), "fem");
  bench::Check(model.Grab(grab, radius), "grab");
  DragResult r;
  for (int i = 1; i <= increments; ++i) {
    const SolveStats s =
        bench::Check(model.Drag(drag * (static_cast<double>(i) / increments)), "drag");
    r.forced |= s.forced_inversion;
    if (s.forced_inversion && std::getenv("MESH_VALIDITY_EXPLAIN") != nullptr) {
      std::printf("  increment %d/%d forced after %d load steps, %d Newton iterations\n", i,
                  increments, s.load_steps, s.newton_iterations);
    }
    r.step_ms += s.total_ms() / increments;
  }
  r.inverted = model.CountInvertedTets();
  if (r.inverted > 0 && std::getenv("MESH_VALIDITY_EXPLAIN") != nullptr) {
    bench::ExplainInvertedTets(model, *explain_volume, grab);
  }
  return r;
}

glm::dvec3 GrabPoint(const Volume& volume) {
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == StandardDrag{}.landmark) return l.position_mm;
  }
  return volume.geometry().extent_mm() * 0.5;
}

void Row(const Volume& volume, const std::string& tf, Footprint footprint, const SolverOptions& live,
         double steiner_deg) {
  explain_volume = &volume;
  MeshParams params;
  params.steiner_min_dihedral_deg = steiner_deg;
  params.hard_reach_factor = hard_reach;
  params.hard_reach_radius_factor = hard_reach_radius;
  params.footprint = footprint;
  if (!tf.empty()) params.tf = tf;
  const glm::dvec3 grab = GrabPoint(volume);
  params.refine_at_mm = grab;
  // Refinement needs 3G voxels per axis: thin volumes (a 54-slice CT) get a
  // coarser G along that axis.
  for (int a = 0; a < 3; ++a) {
    params.grid[a] = std::min<int64_t>(params.grid[a], volume.geometry().dims[a] / 3);
  }
  const glm::dvec3 extent = volume.geometry().extent_mm();
  ProxyMesh mesh;
  const double build_ms =
      bench::MinMs(3, [&] { mesh = bench::Check(BuildProxyMesh(volume, params), "build"); });
  const double h = mesh.stats.h_mm;
  FemOptions interactive;
  interactive.solver = live;
  interactive.material.hard_factor = hard_factor;
  FemOptions measuring = MeasurementFemOptions();
  measuring.material.hard_factor = hard_factor;
  if (measuring_load_steps > 0) measuring.solver.max_load_steps = measuring_load_steps;
  measuring.solver.min_load_fraction = live.min_load_fraction;
  std::string cells;
  double step_ms = 0.0;
  for (const FemOptions* options : std::initializer_list<const FemOptions*>{&interactive, &measuring}) {
    for (double f : {0.5, 1.0, 1.5}) {
      const bool live = options == &interactive;
      const DragResult r = RunDrag(mesh, extent, grab, 0.5 * h, glm::dvec3(0.0, -f * h, 0.0),
                                   *options, live ? 10 : 1);
      cells += StrCat(" ", r.inverted, r.forced ? "f" : "", " ");
      if (live && f == 1.5) step_ms = r.step_ms;
    }
    cells += "|";
  }
  std::printf("%-34s %-6s %5zu %5lld %6zu %8.2f  |%s %9.1f %9.2f\n", volume.source().c_str(),
              FootprintName(footprint), mesh.vertices.size(),
              static_cast<long long>(mesh.stats.steiner), mesh.tets.size(),
              mesh.quality.min_dihedral_deg, cells.c_str(), build_ms, step_ms);
}

}  // namespace

int main(int argc, char** argv) {
  SolverOptions live;
  double steiner_deg = MeshParams{}.steiner_min_dihedral_deg;
  std::vector<std::pair<std::string, std::string>> volumes;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--max-load-steps") == 0 && i + 1 < argc) {
      live.max_load_steps = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--intermediate-newton") == 0 && i + 1 < argc) {
      live.intermediate_newton_iterations = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--min-load-fraction") == 0 && i + 1 < argc) {
      live.min_load_fraction = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--measuring-load-steps") == 0 && i + 1 < argc) {
      measuring_load_steps = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--hard-factor") == 0 && i + 1 < argc) {
      hard_factor = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--hard-reach") == 0 && i + 1 < argc) {
      hard_reach = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--hard-reach-radius") == 0 && i + 1 < argc) {
      hard_reach_radius = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--steiner") == 0 && i + 1 < argc) {
      steiner_deg = std::atof(argv[++i]);
    } else if (i + 1 < argc && std::strchr(argv[i + 1], ':') == nullptr &&
               std::strchr(argv[i + 1], '/') == nullptr && std::strncmp(argv[i + 1], "--", 2)) {
      volumes.emplace_back(argv[i], argv[i + 1]);
      ++i;
    } else {
      volumes.emplace_back(argv[i], "");
    }
  }
  if (volumes.empty()) volumes.emplace_back("phantom:abdomen?size=128", "");
  std::printf("inverted tets after a drag of 0.5 h / 1 h / 1.5 h (f: forced by the drag); "
              "interactive: %d load steps, 10 increments; measuring: at once\n",
              live.max_load_steps);
  std::printf("%-34s %-6s %5s %5s %6s %8s  | %-16s| %-16s| %9s %9s\n", "volume", "foot",
              "verts", "stein", "tets", "min dih", "interactive", "measuring", "build ms", "step ms");
  for (const auto& [source, tf] : volumes) {
    const Volume volume = bench::Check(ReadVolume(source, VolumeLimits{}), "read");
    for (Footprint f : {Footprint::kPoint, Footprint::kCell}) Row(volume, tf, f, live, steiner_deg);
  }
  return 0;
}

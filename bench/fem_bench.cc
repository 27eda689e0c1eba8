// FEM on proxy meshes of the phantom, for meshes of ~250 (+150 refined at
// the landmark), 1,000 and 5,000 vertices:
//   - setup: elements + rest stiffness assembly, SimplicialLDLT factor;
//   - grab of the left_renal_artery landmark with radius 1 h (h = lattice
//     step), then a 12 mm drag in 10 steps: per-step wall and thread-CPU ms,
//     Newton and CG iterations, residual, inverted tets after the drag, and
//     the distance of the final displacement from a tightly converged one;
//   - the per-iteration kernels (forces, K v, factor solve);
//   - validity: inverted tets after drags of 0.5, 1 and 1.5 h.
// Times are the best of --reps runs (the machine is shared).
//
//   fem_bench [SOURCE] [--reps N] [--max-load-steps N] [--min-load-fraction F]
//             [--intermediate-newton N] [--max-vertices N]
//   SOURCE defaults to phantom:abdomen; the other flags: bench/fem_flags.h
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "bench/fem_flags.h"
#include "server/fem/corotated_forces.h"
#include "server/fem/fem_model.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/io/read_volume.h"

using namespace vpm;

namespace {

double CpuMs() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

using bench::Check;
using bench::MinMs;

constexpr double kDragMm = 12.0;
constexpr int kSteps = 10;
const glm::dvec3 kDirection(0.0, 0.0, 1.0);

struct DragResult {
  double step_ms = 0.0;      // wall, assembly + solve, mean over the steps
  double max_step_ms = 0.0;  // wall, slowest step
  double step_cpu_ms = 0.0;  // this thread's CPU time per step, mean
  double newton = 0.0;       // per step, mean
  double cg = 0.0;
  double max_residual = 0.0;
  int unconverged = 0;
  double load_steps = 0.0;  // per step, mean (inversion barrier)
  double shortened = 0.0;   // Newton updates cut by the barrier, per step
  int forced = 0;           // steps whose prescribed motion flattened a tet
  int64_t inverted = 0;     // after the last step
  double grab_ms = 0.0;
  size_t handles = 0;
  std::vector<glm::dvec3> displacement;  // after the last step
};

DragResult Drag(FemModel& model, const glm::dvec3& point, double radius_mm) {
  DragResult r;
  const GrabInfo grab = Check(model.Grab(point, radius_mm), "grab");
  r.grab_ms = grab.setup_ms;
  r.handles = grab.handles.size();
  for (int s = 1; s <= kSteps; ++s) {
    const double cpu0 = CpuMs();
    const SolveStats st = Check(model.Drag(kDirection * (kDragMm * s / kSteps)), "drag");
    r.step_cpu_ms += (CpuMs() - cpu0) / kSteps;
    r.step_ms += st.total_ms() / kSteps;
    r.max_step_ms = std::max(r.max_step_ms, st.total_ms());
    r.newton += static_cast<double>(st.newton_iterations) / kSteps;
    r.cg += static_cast<double>(st.cg_iterations) / kSteps;
    r.max_residual = std::max(r.max_residual, st.residual);
    r.unconverged += !st.converged;
    r.load_steps += static_cast<double>(st.load_steps) / kSteps;
    r.shortened += static_cast<double>(st.shortened_updates) / kSteps;
    r.forced += st.forced_inversion;
  }
  r.inverted = model.CountInvertedTets();
  r.displacement = model.Displacements();
  (void)model.Release();
  return r;
}

// The best (least wall time) of `reps` drags.
DragResult BestDrag(FemModel& model, const glm::dvec3& point, double radius_mm, int reps) {
  DragResult best;
  best.step_ms = std::numeric_limits<double>::infinity();
  for (int r = 0; r < reps; ++r) {
    DragResult run = Drag(model, point, radius_mm);
    if (run.step_ms < best.step_ms) best = std::move(run);
  }
  return best;
}

double MaxDistance(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
  double d = 0.0;
  for (size_t v = 0; v < a.size(); ++v) d = std::max(d, glm::distance(a[v], b[v]));
  return d;
}

void KernelCosts(const FemModel& model, int reps) {
  const CorotationalSolver& solver = model.solver();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * model.vertex_count());
  for (int64_t i = 0; i < u.size(); ++i) u[i] = 0.01 * std::sin(0.1 * static_cast<double>(i));
  CorotatedFrames frames;
  Eigen::VectorXd forces, y, z;
  const auto& elements = solver.elements();
  const double forces_ms =
      MinMs(reps, [&] { CorotatedForces(elements, u, FemMethod::kCorotational, frames, forces); });
  const double twist_ms = MinMs(reps, [&] {
    CorotatedForces(elements, u, FemMethod::kCorotationalConsistent, frames, forces);
  });
  const double matvec_ms = MinMs(reps, [&] { ApplyCorotatedStiffness(elements, frames, u, y); });
  const double matvec2_ms =
      MinMs(reps, [&] { ApplyCorotatedStiffness(elements, frames, u, y, 2); });
  const double precond_ms = MinMs(reps, [&] { solver.factor().Apply(u, false, z); });
  std::printf(
      "  kernels: rotations+forces %.3f ms, with twist %.3f ms, K v %.3f ms "
      "(2 threads %.3f), factor solve %.3f ms (L nnz %lld)\n",
      forces_ms, twist_ms, matvec_ms, matvec2_ms, precond_ms,
      static_cast<long long>(solver.factor().factor_nonzeros()));
}

void PrintRow(const char* mesh_name, const char* variant, const ProxyMesh& mesh,
              const FemModel& model, const DragResult& r, double h, double error_mm) {
  std::printf(
      "%-8s %-14s %6zu %6zu %4zu %7.1f %8.1f %7.1f %5.1f %7.2f %7.2f %7.2f %5.1f %5.1f "
      "%5.1f %5.1f %4d %7.1e %4lld %8.1e%s\n",
      mesh_name, variant, mesh.vertices.size(), model.tets().size(), r.handles,
      model.setup().assembly_ms, model.setup().factor_ms, r.grab_ms, h, r.step_ms, r.step_cpu_ms,
      r.max_step_ms, r.newton, r.cg, r.load_steps, r.shortened, r.forced, r.max_residual,
      static_cast<long long>(r.inverted), error_mm,
      r.unconverged ? "  (some steps hit the iteration limit)" : "");
}

// Inverted tets after drags of 0.5, 1 and 1.5 h (15 steps of 0.1 h).
void Validity(const ProxyMesh& mesh, const Volume& volume, const glm::dvec3& point, double h,
              double radius_h, const SolverOptions& base) {
  FemOptions options;
  options.solver = base;
  FemModel model = Check(FemModel::Create(mesh, volume.geometry().extent_mm(), options), "setup");
  const size_t handles = Check(model.Grab(point, radius_h * h), "grab").handles.size();
  std::printf("  validity, radius %.1f h (%zu handles): inverted tets after", radius_h, handles);
  for (int s = 1; s <= 15; ++s) {
    Check(model.Drag(kDirection * (0.1 * h * s)), "drag");
    if (s % 5 == 0) {
      std::printf(" %.1f h: %lld%s", 0.1 * s, static_cast<long long>(model.CountInvertedTets()),
                  s < 15 ? "," : "\n");
    }
  }
}

struct MeshCase {
  const char* name;
  int64_t grid;
  int64_t target;
  bool refine;
};

void RunCase(const MeshCase& c, const Volume& volume, const glm::dvec3& landmark, int reps,
             const SolverOptions& base) {
  MeshParams params;
  params.grid = {c.grid, c.grid, c.grid};
  params.target = c.target;
  if (c.refine) params.refine_at_mm = landmark;
  const ProxyMesh mesh = Check(BuildProxyMesh(volume, params), "mesh build");
  const double h = mesh.stats.h_mm;
  const glm::dvec3 extent = volume.geometry().extent_mm();
  FemOptions tight;
  tight.solver.update_tolerance = 1e-7;
  tight.solver.cg_tolerance = 1e-7;
  tight.solver.max_newton_iterations = 300;
  FemModel reference_model = Check(FemModel::Create(mesh, extent, tight), "reference setup");
  const DragResult reference = Drag(reference_model, landmark, h);
  struct Variant {
    const char* name;
    FemMethod method;
    int adaptive_twist_after;
    int threads;
    bool barrier = true;
  };
  const SolverOptions defaults;
  const Variant variants[] = {
      {"default", defaults.method, defaults.adaptive_twist_after, 1},
      {"default 2T", defaults.method, defaults.adaptive_twist_after, 2},
      {"twist always", FemMethod::kCorotationalConsistent, 0, 1},
      {"RK0R^T only", FemMethod::kCorotational, 0, 1},
      {"no barrier", defaults.method, defaults.adaptive_twist_after, 1, false}};
  for (const Variant& v : variants) {
    FemOptions options;
    options.solver = base;
    options.solver.method = v.method;
    options.solver.adaptive_twist_after = v.adaptive_twist_after;
    options.solver.threads = v.threads;
    options.solver.inversion_barrier = v.barrier;
    FemModel model = Check(FemModel::Create(mesh, extent, options), "FEM setup");
    const DragResult r = BestDrag(model, landmark, h, reps);
    PrintRow(c.name, v.name, mesh, model, r, h,
             MaxDistance(r.displacement, reference.displacement));
    if (&v == &variants[0]) KernelCosts(model, 5 * reps);
  }
  for (double radius_h : {1.0, 2.0}) Validity(mesh, volume, landmark, h, radius_h, base);
}

}  // namespace

int main(int argc, char** argv) {
  std::string source = "phantom:abdomen";
  int reps = 3;
  bench::FemFlags flags;
  for (int i = 1; i < argc; ++i) {
    if (bench::ParseFemFlag(argc, argv, i, flags)) continue;
    if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else {
      source = argv[i];
    }
  }
  const Volume volume = Check(ReadVolume(source, {}), "reading the volume");
  glm::dvec3 landmark = volume.geometry().extent_mm() * 0.5;
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") landmark = l.position_mm;
  }
  std::printf(
      "FEM drag bench: %s, %.0f mm along (%g, %g, %g) in %d steps at left_renal_artery "
      "(%.1f, %.1f, %.1f) mm, radius 1 h; best of %d runs\n",
      volume.source().c_str(), kDragMm, kDirection.x, kDirection.y, kDirection.z, kSteps,
      landmark.x, landmark.y, landmark.z, reps);
  std::printf(
      "%-8s %-14s %6s %6s %4s %7s %8s %7s %5s %7s %7s %7s %5s %5s %5s %5s %4s %7s %4s %8s\n",
      "mesh", "solver", "verts", "tets", "hdl", "asm ms", "fact ms", "grab ms", "h mm", "step ms",
      "cpu ms", "max ms", "newt", "cg", "load", "short", "forc", "resid", "inv", "err mm");
  const MeshCase cases[] = {
      {"250+150", 20, 250, true}, {"1000", 20, 1000, false}, {"5000", 30, 5000, false}};
  for (const MeshCase& c : cases) {
    if (c.target <= flags.max_vertices) RunCase(c, volume, landmark, reps, flags.solver);
  }
  std::printf(
      "step ms / cpu ms: wall / this thread's CPU time per drag step (mean of %d); "
      "err mm: largest vertex distance from a solve converged to 1e-7; load / short: load steps "
      "and barrier-shortened Newton updates per step; forc: steps whose prescribed motion "
      "flattened a tet (inversion barrier, docs/FEM.md)\n",
      kSteps);
  return 0;
}

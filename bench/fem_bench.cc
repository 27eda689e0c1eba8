// FEM on proxy meshes of the phantom: setup (assembly + factor), grab, and
// a 12 mm drag of the left_renal_artery landmark in 10 steps (radius 1 h),
// for meshes of ~250 (+150 refined), 1,000 and 5,000 vertices; per step the
// solve time, Newton and CG iterations, and the inverted tets after the
// drag. Then the cost of the per-iteration kernels on each mesh.
//
//   fem_bench [SOURCE] [--reps N]    SOURCE defaults to phantom:abdomen
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "server/fem/corotated_forces.h"
#include "server/fem/fem_model.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/volume/read_volume.h"

using namespace vpm;

namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double MinMs(int reps, const std::function<void()>& fn) {
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    best = std::min(best, MsSince(t0));
  }
  return best;
}

template <typename T>
T Check(Result<T> result, const char* what) {
  if (!result.ok()) {
    std::fprintf(stderr, "fem_bench: %s failed: %s\n", what,
                 std::string(result.status().message()).c_str());
    std::exit(1);
  }
  return *std::move(result);
}

struct MeshCase {
  const char* name;
  int64_t grid;
  int64_t target;
  bool refine;
};

struct DragResult {
  double mean_step_ms = 0.0;  // assembly + solve per step, mean over the 10 steps
  double max_step_ms = 0.0;
  double mean_newton = 0.0;
  double mean_cg = 0.0;
  double max_residual = 0.0;
  int unconverged = 0;
  int64_t inverted = 0;  // after the last step
  double max_displacement_mm = 0.0;
};

constexpr double kDragMm = 12.0;
constexpr int kSteps = 10;
const glm::dvec3 kDirection(0.0, 0.0, 1.0);

DragResult Drag(FemModel& model, const glm::dvec3& point, double radius_mm, double& grab_ms,
                size_t& handles) {
  const GrabInfo grab = Check(model.Grab(point, radius_mm), "grab");
  grab_ms = grab.setup_ms;
  handles = grab.handles.size();
  DragResult r;
  for (int s = 1; s <= kSteps; ++s) {
    const SolveStats st = Check(model.Drag(kDirection * (kDragMm * s / kSteps)), "drag");
    r.mean_step_ms += st.total_ms() / kSteps;
    r.max_step_ms = std::max(r.max_step_ms, st.total_ms());
    r.mean_newton += static_cast<double>(st.newton_iterations) / kSteps;
    r.mean_cg += static_cast<double>(st.cg_iterations) / kSteps;
    r.max_residual = std::max(r.max_residual, st.residual);
    r.unconverged += !st.converged;
    r.max_displacement_mm = st.max_displacement_mm;
  }
  r.inverted = model.CountInvertedTets();
  model.Release();
  return r;
}

// Costs of the kernels one Newton iteration and one CG iteration run.
void KernelCosts(const FemModel& model, int reps) {
  const CorotationalSolver& solver = model.solver();
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * model.vertex_count());
  for (int64_t i = 0; i < u.size(); ++i) u[i] = 0.01 * std::sin(0.1 * i);
  CorotatedFrames frames;
  Eigen::VectorXd forces, y, z;
  const double forces_ms = MinMs(reps, [&] {
    CorotatedForces(solver.elements(), u, FemMethod::kCorotational, frames, forces);
  });
  const double forces_twist_ms = MinMs(reps, [&] {
    CorotatedForces(solver.elements(), u, FemMethod::kCorotationalConsistent, frames, forces);
  });
  const double matvec_ms =
      MinMs(reps, [&] { ApplyCorotatedStiffness(solver.elements(), frames, u, y); });
  const double precond_ms = MinMs(reps, [&] { solver.factor().Apply(u, false, z); });
  std::printf(
      "  kernels: forces+rotations %.3f ms (+twist %.3f ms), K*v %.3f ms, "
      "factor solve %.3f ms (factor nnz %lld)\n",
      forces_ms, forces_twist_ms, matvec_ms, precond_ms,
      static_cast<long long>(solver.factor().factor_nonzeros()));
}

}  // namespace

int main(int argc, char** argv) {
  std::string source = "phantom:abdomen";
  int reps = 3;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else {
      source = argv[i];
    }
  }
  const Volume volume = Check(ReadVolume(source, {}), "reading the volume");
  glm::dvec3 landmark(-1.0);
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") landmark = l.position_mm;
  }
  if (landmark.x < 0.0) landmark = volume.geometry().extent_mm() * 0.5;
  std::printf(
      "FEM drag bench: %s, drag %.0f mm along (%g, %g, %g) in %d steps at "
      "left_renal_artery (%.1f, %.1f, %.1f) mm, radius 1 h, min of %d runs\n",
      volume.source().c_str(), kDragMm, kDirection.x, kDirection.y, kDirection.z, kSteps,
      landmark.x, landmark.y, landmark.z, reps);
  const MeshCase cases[] = {
      {"250+150", 20, 250, true}, {"1000", 20, 1000, false}, {"5000", 30, 5000, false}};
  std::printf("%-8s %-12s %6s %6s %5s %8s %8s %7s %7s %9s %9s %6s %6s %8s %4s %6s\n", "mesh",
              "method", "verts", "tets", "hdl", "asm ms", "fact ms", "grab ms", "h mm", "step ms",
              "max ms", "newton", "cg", "resid", "inv", "max mm");
  for (const MeshCase& c : cases) {
    MeshParams params;
    params.grid = {c.grid, c.grid, c.grid};
    params.target = c.target;
    if (c.refine) params.refine_at_mm = landmark;
    const ProxyMesh mesh = Check(BuildProxyMesh(volume, params), "mesh build");
    const double h = mesh.stats.h_mm;
    for (FemMethod method : {FemMethod::kCorotationalConsistent, FemMethod::kCorotational}) {
      FemOptions options;
      options.solver.method = method;
      FemModel model =
          Check(FemModel::Create(mesh, volume.geometry().extent_mm(), options), "FEM setup");
      DragResult best;
      best.mean_step_ms = std::numeric_limits<double>::infinity();
      double grab_ms = std::numeric_limits<double>::infinity();
      size_t handles = 0;
      for (int r = 0; r < reps; ++r) {
        double g = 0.0;
        const DragResult run = Drag(model, landmark, h, g, handles);
        grab_ms = std::min(grab_ms, g);
        if (run.mean_step_ms < best.mean_step_ms) best = run;
      }
      std::printf(
          "%-8s %-12s %6zu %6zu %5zu %8.2f %8.2f %7.2f %7.2f %9.2f %9.2f %6.1f %6.1f "
          "%8.1e %4lld %6.2f%s\n",
          c.name, method == FemMethod::kCorotational ? "RK0R^T" : "RK0R^T+twist",
          mesh.vertices.size(), model.tets().size(), handles, model.setup().assembly_ms,
          model.setup().factor_ms, grab_ms, h, best.mean_step_ms, best.max_step_ms,
          best.mean_newton, best.mean_cg, best.max_residual, static_cast<long long>(best.inverted),
          best.max_displacement_mm,
          best.unconverged ? " (some steps hit the iteration limit)" : "");
      if (method == FemMethod::kCorotationalConsistent) KernelCosts(model, 5 * reps);
    }
  }
  return 0;
}

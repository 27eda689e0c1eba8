// The interactive loop on the phantom, per drag step: FEM solve, backward-map
// update, ray casting (interactive 256x256 and still 512x512), JPEG encode,
// and the frame rate of the whole interactive loop; for the 250-vertex mesh
// refined at the left renal artery, and for ~1,000 and ~5,000 vertices.
//   drag_loop_bench [SOURCE] [--max-load-steps N] [--min-load-fraction F]
//                   [--intermediate-newton N] [--no-barrier] [--max-vertices N]
//                   [--steps] [--map-tolerance MM] [--event-newton-budget N]
//                   [--event-stop-newton N] [--event-max-lag SHARES] [--threads N]
// (bench/fem_flags.h); --steps prints every step's FEM work and stage times.
// The FEM runs with the interactive scene's settings (InteractiveFemOptions:
// at most kInteractiveEventNewtonBudget Newton iterations per step, the rest
// of the motion carried; --event-newton-budget 0 for unbounded steps). After
// the 10th step the drag is settled (DeformableScene::Settle), as before a
// still frame, and the inverted tets are counted there, at 12 mm.
#include <cstdio>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench/bench_util.h"
#include "bench/fem_flags.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/scene/deformable_scene.h"
#include "server/raycast/frame_encoder.h"
#include "server/io/read_volume.h"
#include "server/phantom/phantom_abdomen.h"

using namespace vpm;

namespace {

struct Case {
  const char* name;
  std::array<int64_t, 3> grid;
  int64_t target;
};

// Where the time of a step goes, best of the steps per column (ms).
struct Breakdown {
  double map_gpu = 1e300, map_copy = 1e300;             // map passes (GPU), image copy (wall)
  double clear = 0.0, claim = 1e300, write = 1e300;     // map passes (GPU)
  double texels = 1e300, occupancy = 1e300, cast = 1e300, upscale = 1e300;  // frame, GPU
  double frame_gpu = 1e300, readback = 1e300;           // frame: all kernels, readback (wall)
  double orbit = 1e300;  // wall: interactive frame after an orbit, map unchanged
  int64_t moved = 0, processed = 0;
};

// Where the wall time of a step goes, summed over the steps (ms), and the
// FEM solver's work (counts summed over the steps).
struct Split {
  double forces = 0.0, factor = 0.0, pcg_other = 0.0, fem_other = 0.0;  // FEM parts
  double map = 0.0, frame = 0.0, jpeg = 0.0;
  int64_t newton = 0, cg = 0, load_steps = 0, forced = 0;
  int64_t short_steps = 0;          // steps that stopped short of their offset
  double least_fraction = 1.0;      // the smallest SolveStats::target_fraction
  double largest_lag_mm = 0.0;      // the largest SolveStats::remaining_mm
  double settle_ms = 0.0;           // settling after the 10th step: FEM wall
  int64_t settle_newton = 0;        // and its Newton iterations
};

struct Row {
  double fem = 1e300, map = 1e300, interactive = 1e300, still = 1e300, encode = 1e300;
  double fem_sum = 0.0, fem_max = 0.0;  // over the steps: FEM grows as tets invert
  int steps = 0;
  Breakdown parts;
  Split split;
  double loop_fps = 0.0;
  int64_t vertices = 0, inverted = 0;
  double grab_ms = 0.0, precondition_ms = 0.0;  // grab (handles into the factor), one M^-1 r
  int64_t handles = 0;
};

SceneView InteractiveView(const Volume& volume) {
  return {.camera = Camera::ForVolume(volume.geometry()),
          .preset = bench::Check(MakeRenderPreset("ct-soft-tissue", volume), "preset"),
          .quality = RenderQuality::kInteractive,
          .width = 256,
          .height = 256};
}

// The demo's drag: the left renal artery 12 mm cranially in 10 steps
// (section 3 makes some of its refined vertices hard: docs/MESH.md).
constexpr int kSteps = 10;
glm::dvec3 DragOffset(int step) { return glm::dvec3(0.0, 0.0, 1.2 * step); }

// The drag loop with the map updated once per frame (the server's sessions),
// in order (each step's FEM, then its map update, frame and JPEG) or
// overlapped: the FEM of step N+1 runs on this thread while step N's frame
// is cast and encoded on another (DeformableScene::PrepareRender). Returns
// the loop's frames per second.
// --map-tolerance MM: the backward map's move tolerance (default: the
// interactive map's, InteractiveMapOptions; 0: exact).
double g_map_tolerance_mm = InteractiveMapOptions().move_tolerance_mm;

double RunDeferredLoop(const ProxyMesh& mesh, const Volume& volume,
                       const gpu::GpuContext& context, GpuVolume& gpu_volume,
                       VolumeRenderer& renderer, const glm::dvec3& grab,
                       const SolverOptions& solver, bool overlap) {
  DeformableScene::Options options;
  options.fem.solver = solver;
  options.map.move_tolerance_mm = g_map_tolerance_mm;
  options.defer_map_update = true;
  auto scene = bench::Check(
      DeformableScene::Create(context, volume, gpu_volume, renderer, mesh, options), "scene");
  bench::Check(scene->Grab(grab, mesh.stats.h_mm), "grab");
  const SceneView view = InteractiveView(volume);
  auto render_and_encode = [&](const RenderRequest& request) {
    const Frame frame = bench::Check(scene->RenderPrepared(request), "render");
    bench::Check(EncodeJpeg(frame.rgba, frame.width, frame.height, 85), "jpeg");
  };
  const auto t0 = std::chrono::steady_clock::now();
  bench::Check(scene->Drag(DragOffset(1)), "drag");
  for (int s = 1; s <= kSteps; ++s) {
    const RenderRequest request = bench::Check(scene->PrepareRender(view), "prepare");
    if (!overlap || s == kSteps) {
      render_and_encode(request);
      if (s < kSteps) bench::Check(scene->Drag(DragOffset(s + 1)), "drag");
      continue;
    }
    std::thread frame_thread(render_and_encode, std::cref(request));
    bench::Check(scene->Drag(DragOffset(s + 1)), "drag");
    frame_thread.join();
  }
  return kSteps / (MsSince(t0) / 1000.0);
}

// One drag step's FEM and map figures into row.
void AddStep(const SceneStepTimings& step, Row& row) {
  row.fem = std::min(row.fem, step.fem_ms);
  row.fem_sum += step.fem_ms;
  row.fem_max = std::max(row.fem_max, step.fem_ms);
  row.map = std::min(row.map, step.warp_ms);
  row.inverted = step.inverted_tets;
  const SolveStats& solve = step.solve;
  Split& split = row.split;
  split.forces += solve.assembly_ms;
  split.factor += solve.precondition_ms;
  split.pcg_other += solve.solve_ms - solve.precondition_ms;
  split.fem_other += step.fem_ms - solve.total_ms();
  split.map += step.warp_ms;
  split.newton += solve.newton_iterations;
  split.cg += solve.cg_iterations;
  split.load_steps += solve.load_steps;
  split.forced += solve.forced_inversion ? 1 : 0;
  split.short_steps += solve.target_fraction < 1.0 ? 1 : 0;
  split.least_fraction = std::min(split.least_fraction, solve.target_fraction);
  split.largest_lag_mm = std::max(split.largest_lag_mm, solve.remaining_mm);
}

// The step's interactive frame and its map passes into row's breakdown.
void AddFrame(const SceneStepTimings& step, const Frame& frame, Row& row) {
  row.split.frame += frame.timings.wall_ms;
  row.interactive = std::min(row.interactive, frame.timings.wall_ms);
  Breakdown& b = row.parts;
  const FrameTimings& ft = frame.timings;
  b.map_gpu = std::min(b.map_gpu, step.map_gpu_ms);
  b.map_copy = std::min(b.map_copy, step.map_copy_ms);
  for (const auto& pass : step.map_passes) {
    if (pass.label == "backward_map claim") b.claim = std::min(b.claim, pass.gpu_ms);
    if (pass.label == "backward_map write") b.write = std::min(b.write, pass.gpu_ms);
    if (pass.label == "backward_map clear") b.clear = pass.gpu_ms;
  }
  b.texels = std::min(b.texels, ft.map_copy_ms);
  b.occupancy = std::min(b.occupancy, ft.occupancy_ms);
  b.cast = std::min(b.cast, ft.raycast_ms);
  b.upscale = std::min(b.upscale, ft.upscale_ms);
  b.frame_gpu = std::min(b.frame_gpu, ft.render_ms);
  b.readback = std::min(b.readback, ft.readback_ms);
  b.moved = step.moved_tets;
  b.processed = step.processed_tets;
}

void PrintStep(int s, const SceneStepTimings& step, double frame_ms, double jpeg_ms) {
  const SolveStats& solve = step.solve;
  std::printf(
      "  step %2d: FEM %7.2f ms (forces %6.2f, factor solves %6.2f, K v + PCG %6.2f; "
      "%2d Newton, %3d CG, %2d load steps%s; reached %.3f, %.2f mm to go), map %6.2f, "
      "frame %6.2f, JPEG %5.2f\n",
      s, step.fem_ms, solve.assembly_ms, solve.precondition_ms,
      solve.solve_ms - solve.precondition_ms, solve.newton_iterations, solve.cg_iterations,
      solve.load_steps, solve.forced_inversion ? ", forced" : "", solve.target_fraction,
      solve.remaining_mm, step.warp_ms, frame_ms, jpeg_ms);
}

// The pointer stops at 12 mm: finish the drag (as before a still frame)
// and count the inverted tets there, one solve at a time, as
// DeformableScene::Settle(kSettleSolves) would.
void SettleAfterDrag(DeformableScene& scene, bool print_steps, Row& row) {
  for (int i = 0; i < kSettleSolves && !scene.settled(); ++i) {
    const SceneStepTimings settled = bench::Check(scene.Settle(1), "settle");
    const SolveStats& solve = settled.solve;
    row.split.settle_ms += settled.fem_ms;
    row.split.settle_newton += solve.newton_iterations;
    row.inverted = settled.inverted_tets;
    if (print_steps) {
      std::printf(
          "  settle %d: FEM %7.2f ms (%2d Newton, %3d CG, %2d load steps%s; reached %.3f, "
          "%.2f mm to go), %lld inverted\n",
          i + 1, settled.fem_ms, solve.newton_iterations, solve.cg_iterations, solve.load_steps,
          solve.forced_inversion ? ", forced" : "", solve.target_fraction, solve.remaining_mm,
          static_cast<long long>(settled.inverted_tets));
    }
  }
}

// The grab's cost and one preconditioner application with the handles held
// (per PCG iteration), min of 50.
void TimeGrab(DeformableScene& scene, const ProxyMesh& mesh, const glm::dvec3& grab, Row& row) {
  const auto t_grab = std::chrono::steady_clock::now();
  const GrabInfo grabbed = bench::Check(scene.Grab(grab, mesh.stats.h_mm), "grab");
  row.grab_ms = MsSince(t_grab);
  row.handles = static_cast<int64_t>(grabbed.handles.size());
  const ConstrainedFactor& factor = scene.fem().solver().factor();
  Eigen::VectorXd r = Eigen::VectorXd::Ones(3 * static_cast<int64_t>(mesh.vertices.size()));
  Eigen::VectorXd z;
  row.precondition_ms = bench::MinMs(50, [&] { factor.Apply(r, true, z); });
}

Row RunCase(const ProxyMesh& mesh, const Volume& volume, const gpu::GpuContext& context,
            GpuVolume& gpu_volume, VolumeRenderer& renderer, const glm::dvec3& grab,
            const SolverOptions& solver, bool print_steps) {
  DeformableScene::Options options;
  options.fem.solver = solver;
  options.map.move_tolerance_mm = g_map_tolerance_mm;
  auto scene = bench::Check(
      DeformableScene::Create(context, volume, gpu_volume, renderer, mesh, options), "scene");
  Row row;
  TimeGrab(*scene, mesh, grab, row);
  SceneView interactive = InteractiveView(volume);
  SceneView still = interactive;
  still.quality = RenderQuality::kStill;
  still.width = still.height = 512;
  row.vertices = static_cast<int64_t>(mesh.vertices.size());
  const int steps = kSteps;
  row.steps = steps;
  const auto t_loop = std::chrono::steady_clock::now();
  for (int s = 1; s <= steps; ++s) {
    auto step = bench::Check(scene->Drag(DragOffset(s)), "drag");
    AddStep(step, row);
    auto frame = bench::Check(scene->Render(interactive), "render");
    AddFrame(step, frame, row);
    const auto t0 = std::chrono::steady_clock::now();
    auto jpeg = bench::Check(EncodeJpeg(frame.rgba, frame.width, frame.height, 85), "jpeg");
    const double jpeg_ms = MsSince(t0);
    row.encode = std::min(row.encode, jpeg_ms);
    row.split.jpeg += jpeg_ms;
    if (print_steps) PrintStep(s, step, frame.timings.wall_ms, jpeg_ms);
  }
  row.loop_fps = steps / (MsSince(t_loop) / 1000.0);
  SettleAfterDrag(*scene, print_steps, row);
  // Orbiting between drag steps: same map, so the brick occupancy is reused.
  SceneView orbit = interactive;
  for (int r = 0; r < 3; ++r) {
    orbit.camera.Orbit(2.0, 0.0);
    auto frame = bench::Check(scene->Render(orbit), "orbit");
    row.parts.orbit = std::min(row.parts.orbit, frame.timings.wall_ms);
  }
  for (int r = 0; r < 3; ++r) {
    auto frame = bench::Check(scene->Render(still), "still");
    row.still = std::min(row.still, frame.timings.wall_ms);
  }
  return row;
}

using Rows = std::vector<std::pair<const char*, Row>>;
using Meshes = std::vector<std::pair<const char*, ProxyMesh>>;

// The command line: the source and the FEM flags (bench/fem_flags.h),
// --steps, --no-barrier, --map-tolerance MM; exits on a bad solver option.
struct Args {
  std::string source = "phantom:abdomen";
  bench::FemFlags flags;
  bool print_steps = false;
};

Args ParseArgs(int argc, char** argv) {
  Args a;
  a.flags.solver = InteractiveFemOptions().solver;
  for (int i = 1; i < argc; ++i) {
    if (bench::ParseFemFlag(argc, argv, i, a.flags)) continue;
    if (std::string(argv[i]) == "--steps") {
      a.print_steps = true;
    } else if (std::string(argv[i]) == "--no-barrier") {
      a.flags.solver.inversion_barrier = false;
    } else if (std::string(argv[i]) == "--map-tolerance" && i + 1 < argc) {
      g_map_tolerance_mm = std::atof(argv[++i]);
    } else {
      a.source = argv[i];
    }
  }
  if (const Status status = CheckSolverOptions(a.flags.solver); !status.ok()) {
    std::fprintf(stderr, "drag_loop_bench: %s\n", std::string(status.message()).c_str());
    std::exit(2);
  }
  return a;
}

// The grab: the volume's left renal artery landmark.
glm::dvec3 GrabPoint(const Volume& volume) {
  // A file made from the phantom (bench/make_ct_nifti.cc) carries no
  // landmarks: the phantom's own, placed in this volume's world geometry.
  std::vector<Landmark> landmarks = volume.landmarks();
  if (landmarks.empty()) {
    landmarks = phantom::AbdomenLandmarks(phantom::MakeAbdomenAnatomy(), volume.geometry());
  }
  glm::dvec3 grab(0.0);
  for (const Landmark& l : landmarks) {
    if (l.name == "left_renal_artery") grab = l.position_mm;
  }
  return grab;
}

// The run's set-up and the main table's header.
void PrintSetup(const std::string& source, const gpu::GpuContext& context,
                const SolverOptions& solver) {
  std::printf("drag loop: %s, grab left_renal_artery, drag 12 mm in 10 steps, device '%s'\n",
              source.c_str(), context.device_name().c_str());
  std::printf(
      "FEM: inversion barrier %s, at most %d load steps, min load fraction %g, %d Newton "
      "iterations after a partial load step, at most %d Newton iterations per step (0: "
      "unbounded), %d of them kept for equilibrium where a step stops short, unbounded once "
      "the drag lags over %g event shares (0: never)\n",
      solver.inversion_barrier ? "on" : "off", solver.max_load_steps, solver.min_load_fraction,
      solver.intermediate_newton_iterations, solver.event_newton_budget,
      solver.event_stop_newton_iterations, solver.event_max_lag_shares);
  std::printf("per step, best of the 10 steps (ms; FEM also mean and worst); loop fps = 10 steps "
              "/ their whole wall time (FEM + map + interactive frame + JPEG)\n");
  std::printf("%-22s %6s %8s %9s %8s %8s %13s %11s %8s %9s %9s\n", "mesh", "verts", "FEM",
              "FEM mean", "FEM max", "map", "frame 256^2", "still 512^2", "JPEG", "loop fps",
              "inverted");
}

// The main table, a row per mesh (250, 1,000, 5,000 vertices, up to
// --max-vertices), each mesh built refined at the grab.
Rows RunMeshes(const Args& args, const Volume& volume, const gpu::GpuContext& context,
               GpuVolume& gpu_volume, VolumeRenderer& renderer, const glm::dvec3& grab,
               Meshes& meshes) {
  const SolverOptions& solver = args.flags.solver;
  Rows rows;
  for (const Case& c : {Case{"20^3 -> 250 + refine", {20, 20, 20}, 250},
                        Case{"24^3 -> 1000 + refine", {24, 24, 24}, 1000},
                        Case{"40^3 -> 5000 + refine", {40, 40, 40}, 5000}}) {
    if (c.target > args.flags.max_vertices) continue;
    if (args.print_steps) std::printf("%s:\n", c.name);
    MeshParams params;
    params.grid = c.grid;
    params.target = c.target;
    params.refine_at_mm = grab;
    auto costs = bench::Check(LatticeCostsGpu::Create(context), "kernel");
    meshes.emplace_back(c.name,
                        bench::Check(BuildProxyMesh(volume, params, {&gpu_volume, &costs}), "mesh"));
    const Row r = RunCase(meshes.back().second, volume, context, gpu_volume, renderer, grab, solver,
                          args.print_steps);
    std::printf("%-22s %6lld %8.2f %9.2f %8.2f %8.2f %13.1f %11.1f %8.2f %9.1f %9lld\n", c.name,
                static_cast<long long>(r.vertices), r.fem, r.fem_sum / r.steps, r.fem_max, r.map,
                r.interactive, r.still, r.encode, r.loop_fps, static_cast<long long>(r.inverted));
    rows.emplace_back(c.name, r);
  }
  return rows;
}

void PrintBreakdown(const Rows& rows) {
  std::printf("\nbreakdown, best of the steps (ms): map = GPU passes + image copy (wall) + host;"
              " frame = map to texels + occupancy + cast + upscale (GPU) + readback (wall);"
              " orbit: wall of an interactive frame after a 2-degree orbit (map unchanged)\n");
  std::printf("%-22s %11s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s %8s\n", "mesh", "moved/list",
              "map GPU", "clear", "claim", "write", "map copy", "texels", "occup.", "cast",
              "upscale", "frm GPU", "readback", "orbit");
  for (const auto& [name, r] : rows) {
    const Breakdown& b = r.parts;
    std::printf("%-22s %5lld/%-5lld %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f "
                "%8.2f %8.2f\n",
                name, static_cast<long long>(b.moved), static_cast<long long>(b.processed),
                b.map_gpu, b.clear, b.claim, b.write, b.map_copy, b.texels, b.occupancy, b.cast, b.upscale, b.frame_gpu, b.readback, b.orbit);
  }
}

void PrintSplit(const Rows& rows) {
  std::printf("\nwhere the wall time of a step goes, mean over the steps (ms): FEM = forces "
              "(rotations, elastic forces) + factor solves (preconditioner) + K v and the rest of "
              "PCG + other; then the map update, the interactive frame and its JPEG; per step "
              "also the mean Newton and CG iterations and load steps, and the steps with a "
              "forced inversion\n");
  std::printf("%-22s %8s %8s %8s %8s %8s %8s %8s %8s %8s %6s %6s %6s %6s\n", "mesh", "forces",
              "factor", "Kv+PCG", "FEM etc", "FEM", "map", "frame", "JPEG", "total", "newton",
              "CG", "loads", "forced");
  for (const auto& [name, r] : rows) {
    const Split& p = r.split;
    const double n = r.steps;
    const double fem = p.forces + p.factor + p.pcg_other + p.fem_other;
    std::printf("%-22s %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %8.2f %6.1f %6.1f %6.1f "
                "%6lld\n",
                name, p.forces / n, p.factor / n, p.pcg_other / n, p.fem_other / n, fem / n,
                p.map / n, p.frame / n, p.jpeg / n, (fem + p.map + p.frame + p.jpeg) / n,
                p.newton / n, p.cg / n, p.load_steps / n, static_cast<long long>(p.forced));
  }
}

void PrintEventBound(const Rows& rows, const SolverOptions& solver) {
  std::printf("\nthe per-event bound (--event-newton-budget %d): FEM worst / mean, steps that "
              "stopped short of their offset, the least fraction reached, the largest lag (mm), "
              "then the settle after step 10 (FEM ms, Newton iterations)\n",
              solver.event_newton_budget);
  std::printf("%-22s %10s %6s %9s %8s %10s %8s\n", "mesh", "worst/mean", "short", "reached",
              "lag mm", "settle ms", "newton");
  for (const auto& [name, r] : rows) {
    const Split& p = r.split;
    std::printf("%-22s %10.2f %6lld %9.3f %8.2f %10.2f %8lld\n", name,
                r.fem_max / (r.fem_sum / r.steps), static_cast<long long>(p.short_steps),
                p.least_fraction, p.largest_lag_mm, p.settle_ms,
                static_cast<long long>(p.settle_newton));
  }
}

void PrintHandles(const Rows& rows, const SolverOptions& solver) {
  std::printf("\nthe grab's handles in the preconditioner (--handle-factor %s): grab ms, one "
              "application ms (min of 50)\n",
              solver.handle_factor == HandleFactor::kRefactor ? "refactor" : "capacitance");
  std::printf("%-22s %8s %8s %10s\n", "mesh", "handles", "grab", "M^-1 r");
  for (const auto& [name, r] : rows) {
    std::printf("%-22s %8lld %8.2f %10.3f\n", name, static_cast<long long>(r.handles), r.grab_ms,
                r.precondition_ms);
  }
}

// The deferred loop in order against overlapped (RunDeferredLoop).
void PrintOverlap(const Meshes& meshes, const Volume& volume, const gpu::GpuContext& context,
                  GpuVolume& gpu_volume, VolumeRenderer& renderer, const glm::dvec3& grab,
                  const SolverOptions& solver) {
  std::printf("\noverlap: the loop with the map updated once per frame, in order (FEM, map, "
              "frame, JPEG) and with the FEM of step N+1 running while frame N is cast and "
              "encoded (loop fps, best of 3)\n");
  std::printf("%-22s %10s %10s %8s\n", "mesh", "in order", "overlap", "gain");
  for (const auto& [name, mesh] : meshes) {
    double fps[2] = {0.0, 0.0};
    for (int r = 0; r < 3; ++r) {
      for (int overlap = 0; overlap < 2; ++overlap) {
        fps[overlap] =
            std::max(fps[overlap], RunDeferredLoop(mesh, volume, context, gpu_volume, renderer,
                                                   grab, solver, overlap == 1));
      }
    }
    std::printf("%-22s %10.1f %10.1f %7.2fx\n", name, fps[0], fps[1], fps[1] / fps[0]);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = ParseArgs(argc, argv);
  const SolverOptions& solver = args.flags.solver;
  auto volume = bench::Check(ReadVolume(args.source, {}), "reading the volume");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  auto gpu_volume = bench::Check(GpuVolume::Upload(*context, volume), "upload");
  auto renderer = bench::Check(VolumeRenderer::Create(*context, {}), "renderer");
  const glm::dvec3 grab = GrabPoint(volume);
  PrintSetup(args.source, *context, solver);
  Meshes meshes;
  const Rows rows = RunMeshes(args, volume, *context, gpu_volume, *renderer, grab, meshes);
  PrintBreakdown(rows);
  PrintSplit(rows);
  PrintEventBound(rows, solver);
  PrintHandles(rows, solver);
  PrintOverlap(meshes, volume, *context, gpu_volume, *renderer, grab, solver);
  return 0;
}

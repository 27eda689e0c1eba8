// What each way of casting interactive frames costs and shows, during a
// drag: for each candidate (InteractiveCast: ray grid divisor, step, upscale
// filter) the drag loop's frames per second (FEM step + map update +
// interactive frame + JPEG, in order, as drag_loop_bench's loop), the
// frame's wall time, its two kernels' times (occupancy, ray cast; GPU
// timestamps), the values each ray read (RaycastSettings::count_samples),
// and its PSNR (RGB) against the still of the same deformed state and
// camera. 512 x 512 (--size), default camera, the
// 250-vertex mesh refined at the grab (the phantom's left renal artery, the
// kidney CT's left kidney), dragged 12 mm in 10 steps. Candidates run interleaved, rep by rep, in
// one process, so that other load on the machine weighs on all alike; the load average is printed
// before and after each volume. Usage: interactive_quality_bench [--candidates] [--reps N] [--size
// N]
//                                  [--ladder] [--preset NAME] [--mode dvr|mip] [--cut]
//                                  [--whole-end-steps] [SOURCE...]
//   --candidates: also the casts that were measured against the settings
//   (InteractiveQuality), not only fast, balanced and sharp;
//   --ladder: instead, the refinement at rest (refine_ladder.h): after the
//   drag, settled, each interactive setting, candidate rungs and the still,
//   frame ms and PSNR against the still;
//   --cut: every frame and still with the view cut (SceneView::view_cut),
//   as the clients open; --whole-end-steps: a ray's first sample a whole
//   step of its value and nothing past its last, stills too
//   (RaycastSettings::partial_end_steps off; not with --ladder);
//   SOURCE: a volume file or phantom:NAME (default: the kidney CT and
//   phantom:abdomen).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "server/io/read_volume.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/raycast/frame_encoder.h"
#include "server/scene/deformable_scene.h"

using namespace vpm;

namespace {

struct Candidate {
  std::string name;
  InteractiveCast cast;
  bool jitter = true;  // ray starts jittered, a new seed per frame
};

std::vector<Candidate> Candidates(bool all) {
  const int bilinear = gpu::kUpscaleBilinear, cubic = gpu::kUpscaleCatmullRom;
  std::vector<Candidate> c = {
      {"fast", InteractiveCastFor(InteractiveQuality::kFast)},
      {"balanced", InteractiveCastFor(InteractiveQuality::kBalanced)},
      {"sharp", InteractiveCastFor(InteractiveQuality::kSharp)},
  };
  if (!all) return c;
  for (const Candidate& more : std::vector<Candidate>{
           {"1/2 res, footprint step, no jitter", {2.0, 0.0, bilinear}, false},
           {"1/2 res, footprint step, Catmull-Rom", {2.0, 0.0, cubic}},
           {"1/2 res, step <= 2x still, Catmull-Rom", {2.0, 2.0, cubic}},
           {"1/2 res, step <= 1.5x still", {2.0, 1.5, bilinear}},
           {"2/3 res, step <= 2x still", {1.5, 2.0, bilinear}},
           {"2/3 res, step <= 1.5x still", {1.5, 1.5, bilinear}},
           {"2/3 res, step <= 3x still", {1.5, 3.0, bilinear}},
           {"full res, footprint step", {1.0, 0.0, bilinear}},
           {"full res, step <= 2x still", {1.0, 2.0, bilinear}},
           {"full res, step <= 3x still", {1.0, 3.0, bilinear}},
           {"full res, step <= 4x still", {1.0, 4.0, bilinear}},
       }) {
    c.push_back(more);
  }
  return c;
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  in >> one >> five >> fifteen;
  return one + " " + five + " " + fifteen;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Result_ {
  double mse_sum = 0.0, worst_db = 99.0;
  int frames = 0;
  double step_mm = 0.0;
  int rays = 0;
  std::vector<double> fps, frame_ms;
  std::vector<double> occupancy_ms, cast_ms;  // the frame's two kernels (GPU timestamps)
  double samples_per_ray = 0.0;               // mean over the PSNR pass's frames
};

constexpr int kSteps = 10;
glm::dvec3 DragOffset(int step) { return glm::dvec3(0.0, 0.0, 1.2 * step); }

// Where the drag grabs: the volume's left renal artery landmark; for a file
// with a left_kidney_mask.nii.gz beside it (the kidney CT), the mask voxel
// nearest the mask's centroid; else the box centre.
glm::dvec3 GrabPoint(const std::string& source, const Volume& volume) {
  const VolumeGeometry& g = volume.geometry();
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") return l.position_mm;
  }
  const std::string mask_path =
      source.substr(0, source.find_last_of('/') + 1) + "left_kidney_mask.nii.gz";
  if (source.find('/') != std::string::npos && std::ifstream(mask_path).good()) {
    const Volume mask = bench::Check(ReadVolume(mask_path, {}), "reading the kidney mask");
    std::vector<glm::dvec3> inside;
    glm::dvec3 centroid(0.0);
    for (int64_t k = 0; k < g.dims[2]; ++k)
      for (int64_t j = 0; j < g.dims[1]; ++j)
        for (int64_t i = 0; i < g.dims[0]; ++i) {
          if (mask.At(i, j, k) < 0.5f) continue;
          inside.push_back(g.IndexToPhysical(glm::dvec3(i, j, k)));
          centroid += inside.back();
        }
    if (!inside.empty()) {
      centroid /= double(inside.size());
      glm::dvec3 best = inside.front();
      for (const glm::dvec3& p : inside) {
        if (glm::distance(p, centroid) < glm::distance(best, centroid)) best = p;
      }
      return best;
    }
  }
  return 0.5 * g.extent_mm();
}

// What both measurements share: the volume on the GPU, a renderer, the
// grab point and the mesh refined there.
struct Fixture {
  explicit Fixture(Volume v) : volume(std::move(v)) {}
  Volume volume;
  std::unique_ptr<gpu::GpuContext> context;
  std::optional<GpuVolume> gpu_volume;
  std::unique_ptr<VolumeRenderer> renderer;
  glm::dvec3 grab{0.0};
  ProxyMesh mesh;
  DeformableScene::Options options;

  // A scene with the grab taken and dragged `steps` steps.
  std::unique_ptr<DeformableScene> DraggedScene(int steps) {
    auto scene = bench::Check(
        DeformableScene::Create(*context, volume, *gpu_volume, *renderer, mesh, options), "scene");
    bench::Check(scene->Grab(grab, mesh.stats.h_mm), "grab");
    for (int s = 1; s <= steps; ++s) bench::Check(scene->Drag(DragOffset(s)), "drag");
    return scene;
  }
};

std::unique_ptr<Fixture> MakeFixture(const std::string& source) {
  auto f = std::make_unique<Fixture>(bench::Check(ReadVolume(source, {}), "reading the volume"));
  f->context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  f->gpu_volume.emplace(bench::Check(GpuVolume::Upload(*f->context, f->volume), "upload"));
  f->renderer = bench::Check(VolumeRenderer::Create(*f->context, {}), "renderer");
  f->grab = GrabPoint(source, f->volume);
  MeshParams params;
  params.grid = {20, 20, 20};
  params.target = 250;
  params.refine_at_mm = f->grab;
  auto costs = bench::Check(LatticeCostsGpu::Create(*f->context), "kernel");
  f->mesh = bench::Check(BuildProxyMesh(f->volume, params, {&*f->gpu_volume, &costs}), "mesh");
  f->options.fem = InteractiveFemOptions();
  f->options.map = InteractiveMapOptions();
  return f;
}

// Candidate c's frame of the scene's current state (c < 0: the still),
// counting its samples when asked.
using RenderCandidate = std::function<Frame(DeformableScene&, int, bool)>;

// PSNR: every candidate's frame against the still, at each drag step.
void MeasurePsnr(Fixture& f, const RenderCandidate& render, std::vector<Result_>& results) {
  auto scene = f.DraggedScene(0);
  for (int s = 1; s <= kSteps; ++s) {
    bench::Check(scene->Drag(DragOffset(s)), "drag");
    const Frame reference = render(*scene, -1, false);
    for (size_t c = 0; c < results.size(); ++c) {
      const Frame frame = render(*scene, int(c), true);
      const double mse = bench::RgbMse(frame.rgba, reference.rgba);
      Result_& r = results[c];
      r.mse_sum += mse;
      r.worst_db = std::min(r.worst_db, bench::PsnrOfMse(mse));
      ++r.frames;
      r.step_mm = frame.step_mm;
      r.rays = frame.render_width;
      r.samples_per_ray +=
          double(frame.samples) / (double(frame.render_width) * frame.render_height * kSteps);
    }
  }
}

// Frame rate: the drag loop per candidate, interleaved rep by rep.
void MeasureRates(Fixture& f, const RenderCandidate& render, int reps,
                  std::vector<Result_>& results) {
  for (int rep = 0; rep < reps; ++rep) {
    for (size_t c = 0; c < results.size(); ++c) {
      auto scene = f.DraggedScene(0);
      const auto t0 = std::chrono::steady_clock::now();
      for (int s = 1; s <= kSteps; ++s) {
        bench::Check(scene->Drag(DragOffset(s)), "drag");
        const Frame frame = render(*scene, int(c), false);
        results[c].frame_ms.push_back(frame.timings.wall_ms);
        results[c].occupancy_ms.push_back(frame.timings.occupancy_ms);
        results[c].cast_ms.push_back(frame.timings.raycast_ms);
        bench::Check(EncodeJpeg(frame.rgba, frame.width, frame.height, 85), "jpeg");
      }
      results[c].fps.push_back(kSteps / (MsSince(t0) / 1000.0));
    }
  }
}

void RunVolume(const std::string& source, int reps, int size, const std::string& preset,
               RenderMode mode, bool all, bool cut, bool whole_end_steps) {
  const std::unique_ptr<Fixture> f = MakeFixture(source);
  const Volume& volume = f->volume;
  auto& context = f->context;
  SceneView view{.camera = Camera::ForVolume(volume.geometry()),
                 .mode = mode,
                 .preset = bench::Check(MakeRenderPreset(preset, volume), "preset"),
                 .quality = RenderQuality::kInteractive,
                 .width = size,
                 .height = size,
                 .view_cut = cut};
  SceneView still = view;
  still.quality = RenderQuality::kStill;
  const std::vector<Candidate> candidates = Candidates(all);
  // Candidate c's frame (c < 0: the still) of the scene's current state.
  const RenderCandidate render = [&](DeformableScene& scene, int c, bool count) {
    RenderRequest request = bench::Check(scene.PrepareRender(c < 0 ? still : view), "prepare");
    if (c >= 0) {
      request.interactive = candidates[c].cast;
      request.settings.jitter = candidates[c].jitter;
    }
    request.settings.partial_end_steps = !whole_end_steps;
    request.settings.count_samples = count;
    return bench::Check(scene.RenderPrepared(request), c < 0 ? "still" : "frame");
  };
  std::vector<Result_> results(candidates.size());
  const std::string load_before = LoadAverage();

  MeasurePsnr(*f, render, results);
  MeasureRates(*f, render, reps, results);
  std::printf("\n%s, %s %s, %dx%d%s%s, device '%s'; load average before %s, after %s\n",
              source.c_str(), mode == RenderMode::kMip ? "MIP" : "DVR", preset.c_str(), size,
              size, cut ? ", view cut" : "", whole_end_steps ? ", whole end steps" : "",
              context->device_name().c_str(), load_before.c_str(), LoadAverage().c_str());
  std::printf("%-40s %5s %7s %9s %9s %10s %8s %8s %9s %9s %9s\n", "candidate", "rays",
              "step mm", "loop fps", "(best)", "frame ms", "occ ms", "cast ms", "reads/ray",
              "PSNR dB", "worst dB");
  for (size_t c = 0; c < candidates.size(); ++c) {
    const Result_& r = results[c];
    std::printf("%-40s %5d %7.3f %9.1f %9.1f %10.1f %8.1f %8.1f %9.1f %9.1f %9.1f\n",
                candidates[c].name.c_str(), r.rays, r.step_mm, Median(r.fps),
                *std::max_element(r.fps.begin(), r.fps.end()), Median(r.frame_ms),
                Median(r.occupancy_ms), Median(r.cast_ms), r.samples_per_ray,
                bench::PsnrOfMse(r.mse_sum / r.frames),
                r.worst_db);
  }
}

// The refinement ladder at rest (refine_ladder.h): after the drag, settled
// as a still settles, each cast's frame ms (median over `reps`, interleaved)
// and PSNR against the still: the interactive settings (what the rungs
// follow), candidate rungs at k x the still's step, and the still.
void RunLadder(const std::string& source, int reps, int size, const std::string& preset,
               RenderMode mode) {
  const std::unique_ptr<Fixture> f = MakeFixture(source);
  auto scene = f->DraggedScene(kSteps);
  bench::Check(scene->Settle(kSettleSolves), "settle");
  SceneView still{.camera = Camera::ForVolume(f->volume.geometry()),
                  .mode = mode,
                  .preset = bench::Check(MakeRenderPreset(preset, f->volume), "preset"),
                  .width = size,
                  .height = size};
  struct Cast {
    std::string name;
    SceneView view;
  };
  std::vector<Cast> casts;
  for (const auto& [name, quality] : {std::pair{"fast (moving)", InteractiveQuality::kFast},
                                      {"balanced (moving)", InteractiveQuality::kBalanced},
                                      {"sharp (moving)", InteractiveQuality::kSharp}}) {
    casts.push_back({name, still});
    casts.back().view.quality = RenderQuality::kInteractive;
    casts.back().view.interactive_quality = quality;
  }
  for (const double k : {4.0, 3.0, 2.0, 1.5}) {
    casts.push_back({StrCat("rung: step ", k, "x still"), still});
    casts.back().view.refine_step_multiple = k;
  }
  casts.push_back({"still", still});
  const std::string load_before = LoadAverage();
  const Frame reference = bench::Check(scene->Render(still), "still");
  std::vector<std::vector<double>> ms(casts.size());
  std::vector<Frame> frames(casts.size());
  for (int rep = 0; rep < reps; ++rep) {
    for (size_t c = 0; c < casts.size(); ++c) {
      frames[c] = bench::Check(scene->Render(casts[c].view), "frame");
      ms[c].push_back(frames[c].timings.wall_ms);
    }
  }
  std::printf("\n%s, refinement at rest, %s %s, %dx%d; load average before %s, after %s\n",
              source.c_str(), mode == RenderMode::kMip ? "MIP" : "DVR", preset.c_str(), size,
              size, load_before.c_str(), LoadAverage().c_str());
  std::printf("%-28s %5s %7s %10s %9s\n", "cast", "rays", "step mm", "frame ms", "PSNR dB");
  for (size_t c = 0; c < casts.size(); ++c) {
    std::printf("%-28s %5d %7.3f %10.1f %9.1f\n", casts[c].name.c_str(), frames[c].render_width,
                frames[c].step_mm, Median(ms[c]),
                bench::PsnrOfMse(bench::RgbMse(frames[c].rgba, reference.rgba)));
  }
}

}  // namespace

int main(int argc, char** argv) {
  int reps = 3, size = 512;
  bool all = false, ladder = false, cut = false, whole_end_steps = false;
  std::string preset = "ct-soft-tissue";
  RenderMode mode = RenderMode::kDvr;
  std::vector<std::string> sources;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--candidates") {
      all = true;
    } else if (a == "--ladder") {
      ladder = true;
    } else if (a == "--cut") {
      cut = true;
    } else if (a == "--whole-end-steps") {
      whole_end_steps = true;
    } else if (a == "--reps" && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--size" && i + 1 < argc) {
      size = std::atoi(argv[++i]);
    } else if (a == "--preset" && i + 1 < argc) {
      preset = argv[++i];
    } else if (a == "--mode" && i + 1 < argc) {
      mode = std::string(argv[++i]) == "mip" ? RenderMode::kMip : RenderMode::kDvr;
    } else {
      sources.push_back(a);
    }
  }
  if (sources.empty()) {
    sources = {"tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz", "phantom:abdomen"};
  }
  std::printf(
      "interactive frames during a drag (phantom: left renal artery, kidney CT: left kidney; 12 mm "
      "in 10 steps, 250-vertex "
      "mesh): loop fps = 10 steps / their wall time (FEM + map + frame + JPEG), median "
      "and best of %d; frame ms: median wall of the interactive frame; PSNR (RGB) against "
      "the still of the same deformed state and camera, over the 10 steps (worst: the "
      "worst step)\n",
      reps);
  for (const std::string& source : sources) {
    if (ladder) {
      RunLadder(source, reps, size, preset, mode);
    } else {
      RunVolume(source, reps, size, preset, mode, all, cut, whole_end_steps);
    }
  }
  return 0;
}

// Ray casting of the 256^3 phantom (or argv[1]) through an identity backward
// map: GPU kernel time against the CPU reference (2 threads) on the same
// frame in one run (runs alternate, minimum of 5 each), with empty-space skipping on and off, still
// 512x512 and interactive (512x512 shown, 256x256 cast), texel-buffer and sampler3D volume reads;
// then JPEG (quality 85) and PNG encoding of the still frame. Usage: render_bench [--render-tf
// FILE] [--step MM] [--window W L]
//                     [--no-reference] [--map-held] [--no-map] [--band-rays N] [--band-ms MS]
//                     [--no-early-termination] [--light-back-end] [--whole-end-steps]
//                     [SOURCE] [PNG_DIR] [FILTER] [SIZE]
//   --render-tf: adds the rows "still DVR custom" and "interactive DVR
//   custom", DVR with the transfer function of FILE (ParaView .json[#NAME]
//   or Slicer .vp);
//   --step: the sample step of every row, still and interactive (mm; default:
//   each quality's own); --window: the MIP window (default: the volume's);
//   --no-reference: GPU only, no CPU reference (bench/peer_vtk.py);
//   --map-held: every row keeps the map unchanged (its occupancy is computed
//   once and reused, as while orbiting or for a still after a drag);
//   --no-map: every row without the map (what DeformableScene renders while
//   nothing is deformed); --band-rays N: still frames cast in bands of about
//   N rays (default kStillBandRays; 0: one band); --band-ms MS: bands of
//   about MS ms at the last still's cost where that makes more, and the
//   bands after the first submitted in groups of about MS ms at the first
//   band's time (default kStillBandMs; 0: bands by rays, one submit each);
//   --no-early-termination: every ray to its end (the exact integral that a
//   fine step's reference approaches); --light-back-end: pre-integrated
//   steps lit by the light at their back end alone
//   (RaycastSettings::light_both_ends off); --whole-end-steps: a ray's
//   first sample a whole step of its value and nothing past its last
//   (RaycastSettings::partial_end_steps off);
//   PNG_DIR: where to write the frames ("" for nowhere); FILTER: only the
//   rows whose name contains it, or one of several separated by '|' (a part
//   ending in '$' must end the name: "still MIP$|still DVR ct-bone$");
//   SIZE: frame side (default 512).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "server/raycast/frame_encoder.h"
#include "server/raycast/raycast_cpu.h"
#include "server/raycast/volume_renderer.h"
#include "server/io/read_render_transfer_function.h"
#include "server/io/read_volume.h"
#include "server/raycast/render_preset_from_tf.h"
#include "server/raycast/volume_mip_window.h"

using namespace vpm;

namespace {

constexpr const char* kCustomPreset = "custom";

struct Case {
  std::string name;
  RenderMode mode;
  const char* preset;  // a preset name, or kCustomPreset (--render-tf)
  RenderQuality quality;
  bool skipping;
  bool shading = true;
  bool map = true;
  VolumeAccess access = VolumeAccess::kTexelBuffer;
  bool cell_gradient = true;  // DVR shading: cell gradient, else central-difference taps
  bool brightest_first = true;  // MIP: RaycastSettings::mip_brightest_first
  bool peak_refine = true;      // MIP: RaycastSettings::mip_peak_refine
};

struct Measured {
  double gpu_raycast_ms = 1e300;  // timestamps, min over reps
  double gpu_total_ms = 1e300;    // every kernel of the frame
  double gpu_map_copy_ms = 1e300;  // the frame's other kernels, min over reps each
  double gpu_occupancy_ms = 1e300;
  double gpu_upscale_ms = 1e300;
  double wall_ms = 1e300;         // Render() incl. readback
  double cpu_ms = 1e300;          // reference, occupancy + ray cast + upscale
  // Process CPU time / 2 cores: what the wall time would be on an idle
  // 2-core machine, measurable while other processes load it.
  double gpu_cpu_time_ms = 1e300;
  double cpu_cpu_time_ms = 1e300;
  double mean_err = 0, max_err = 0;
  Frame frame;
};

double ProcessCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

void WritePng(const std::string& dir, const std::string& name, const Frame& f) {
  if (dir.empty()) return;
  auto png = bench::Check(EncodePng(f.rgba, f.width, f.height), "png");
  std::ofstream(dir + "/" + name + ".png", std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), std::streamsize(png.size()));
}

// Oblique views of every preset, and the anterior ct-vessels view with a
// mesh-like overlay (a 10 x 10 x 8 point lattice, bone points hard, one
// handle near the left kidney dragged 30 mm to the left), for looking at.
void WriteViews(const std::string& dir, const Volume& volume, const GpuVolume& gpu_volume,
                VolumeRenderer& renderer) {
  for (const char* preset : {"ct-soft-tissue", "ct-bone", "ct-vessels", "mri-t1"}) {
    for (RenderMode mode : {RenderMode::kDvr, RenderMode::kMip}) {
      RenderRequest r;
      r.camera = Camera::ForVolume(volume.geometry());
      r.camera.Orbit(35.0, 20.0);
      r.mode = mode;
      r.preset = bench::Check(MakeRenderPreset(preset, volume), "preset");
      r.volume = &gpu_volume;
      const Frame f = bench::Check(renderer.Render(r), "render");
      WritePng(dir, std::string("oblique_") + preset + (mode == RenderMode::kMip ? "_mip" : ""), f);
    }
  }
  RenderRequest r;
  r.camera = Camera::ForVolume(volume.geometry());
  r.preset = bench::Check(MakeRenderPreset("ct-vessels", volume), "preset");
  r.volume = &gpu_volume;
  const glm::dvec3 extent = volume.geometry().extent_mm();
  glm::dvec3 kidney = 0.5 * extent;
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_kidney_center") kidney = l.position_mm;
  }
  double best = 1e300;
  for (int c = 0; c < 8; ++c)
    for (int b = 0; b < 10; ++b)
      for (int a = 0; a < 10; ++a) {
        const glm::dvec3 pos = glm::dvec3(a / 9.0, b / 9.0, c / 7.0) * extent;
        const glm::dvec3 index = glm::round(volume.geometry().PhysicalToIndex(pos));
        const bool hard = volume.At(int64_t(index.x), int64_t(index.y), int64_t(index.z)) > 250;
        r.overlay.points.push_back({pos, hard, VertexKind::kLattice, false});
        const double d = glm::length(pos - kidney);
        if (d < best) best = d;
      }
  for (auto& p : r.overlay.points) p.handle = glm::length(p.position_mm - kidney) == best;
  r.overlay.points.push_back({kidney, false, VertexKind::kRefined, false});
  r.overlay.drag = DragArrow{kidney, kidney + glm::dvec3(30.0, 0.0, 0.0)};
  WritePng(dir, "overlay_ct_vessels", bench::Check(renderer.Render(r), "render"));
}

// Whether a row or section name passes FILTER (see the usage above).
bool Matches(const std::string& name, const std::string& filter) {
  size_t begin = 0;
  for (;;) {
    const size_t end = std::min(filter.find('|', begin), filter.size());
    std::string part = filter.substr(begin, end - begin);
    const bool anchored = !part.empty() && part.back() == '$';
    if (anchored) part.pop_back();
    if (anchored ? name.size() >= part.size() &&
                       name.compare(name.size() - part.size(), part.size(), part) == 0
                 : name.find(part) != std::string::npos) {
      return true;
    }
    if (end == filter.size()) return false;
    begin = end + 1;
  }
}

// Channel-by-channel difference of two RGBA8 frames over RGB.
struct Difference {
  double mean = 0.0, max = 0.0, psnr_db = 99.0;
};

Difference Compare(const Frame& a, const Frame& b) {
  double sum = 0.0, sq = 0.0, max = 0.0;
  size_t count = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    const double d = std::abs(double(a.rgba[i]) - double(b.rgba[i]));
    sum += d;
    sq += d * d;
    max = std::max(max, d);
    ++count;
  }
  return {sum / double(count), max,
          sq > 0.0 ? 10.0 * std::log10(255.0 * 255.0 * double(count) / sq) : 99.0};
}

double ParseNumber(const char* text, const char* flag) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v)) {
    std::fprintf(stderr, "render_bench: %s takes a number, not '%s'\n", flag, text);
    std::exit(2);
  }
  return v;
}

// The command line (see the usage above).
struct Flags {
  std::string render_tf;
  double step_mm = 0.0;
  std::optional<MipWindow> window;
  bool reference = true;
  bool map_held = false;
  bool no_map = false;
  int64_t band_rays = kStillBandRays;
  double band_ms = kStillBandMs;
  bool early_termination = true;
  bool light_both_ends = true;
  bool partial_end_steps = true;
  std::string source = "phantom:abdomen";
  std::string png_dir;
  std::string filter;
  int size = 512;
};

// Flags anywhere; the rest are positional.
Flags ParseFlags(int argc, char** argv) {
  Flags f;
  std::vector<std::string> positional;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--render-tf" && i + 1 < argc) {
      f.render_tf = argv[++i];
    } else if (arg == "--step" && i + 1 < argc) {
      f.step_mm = ParseNumber(argv[++i], "--step");
    } else if (arg == "--window" && i + 2 < argc) {
      const double width = ParseNumber(argv[++i], "--window");
      f.window = MipWindow{.level = ParseNumber(argv[++i], "--window"), .width = width};
    } else if (arg == "--band-rays" && i + 1 < argc) {
      f.band_rays = int64_t(ParseNumber(argv[++i], "--band-rays"));
    } else if (arg == "--band-ms" && i + 1 < argc) {
      f.band_ms = ParseNumber(argv[++i], "--band-ms");
    } else if (arg == "--no-reference" || arg == "--map-held" || arg == "--no-map" ||
               arg == "--no-early-termination" || arg == "--light-back-end" ||
               arg == "--whole-end-steps") {
      f.reference &= arg != "--no-reference";
      f.map_held |= arg == "--map-held";
      f.no_map |= arg == "--no-map";
      f.early_termination &= arg != "--no-early-termination";
      f.light_both_ends &= arg != "--light-back-end";
      f.partial_end_steps &= arg != "--whole-end-steps";
    } else {
      positional.push_back(arg);
    }
  }
  if (positional.size() > 0) f.source = positional[0];
  if (positional.size() > 1) f.png_dir = positional[1];
  if (positional.size() > 2) f.filter = positional[2];
  if (positional.size() > 3) f.size = std::atoi(positional[3].c_str());
  return f;
}

// The volume on the GPU, an identity backward map at the warp's default
// resolution (ceil(n / 4) per axis, docs/WARP.md: 64^3 for the 256^3
// phantom), both renderers, the reference's brick grids and the
// --render-tf preset.
struct Fixture {
  explicit Fixture(Volume v) : volume(std::move(v)) {}
  Volume volume;
  std::unique_ptr<gpu::GpuContext> context;
  std::optional<GpuVolume> gpu_volume;
  const gpu::GpuImage3D* volume_image = nullptr;
  uint32_t m = 2;
  std::optional<gpu::GpuImage3D> map;
  HostBackwardMap host_map;
  std::unique_ptr<VolumeRenderer> texel_renderer, sampled_renderer;
  double create_ms = 0.0;
  std::vector<glm::vec2> still_minmax, interactive_minmax;
  std::optional<RenderPreset> custom;
};

std::unique_ptr<Fixture> MakeFixture(const Flags& flags) {
  auto f =
      std::make_unique<Fixture>(bench::Check(ReadVolume(flags.source, {}), "reading the volume"));
  const Volume& volume = f->volume;
  f->context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  f->gpu_volume.emplace(bench::Check(GpuVolume::Upload(*f->context, volume), "upload"));
  std::printf("volume: %s voxels\n", VoxelEncodingName(volume.encoding()));
  f->volume_image = bench::Check(f->gpu_volume->Image(*f->context, volume), "image");
  const uint32_t m = f->m = uint32_t(std::max<int64_t>(2, (volume.dims()[0] + 3) / 4));
  f->map.emplace(bench::Check(
      gpu::GpuImage3D::Create(*f->context, {m, m, m}, vk::Format::eR32G32B32A32Sfloat), "map"));
  f->host_map = {{int(m), int(m), int(m)},
                 std::vector<glm::vec4>(size_t(m) * m * m, glm::vec4(0, 0, 0, 1))};
  bench::Check(f->map->Upload(std::as_bytes(std::span<const glm::vec4>(f->host_map.texels))),
               "map upload");
  const auto t0 = std::chrono::steady_clock::now();
  f->texel_renderer = bench::Check(
      VolumeRenderer::Create(*f->context,
                             {.still_band_rays = flags.band_rays, .still_band_ms = flags.band_ms}),
      "renderer");
  f->create_ms = MsSince(t0);
  f->sampled_renderer =
      bench::Check(VolumeRenderer::Create(*f->context, {.volume_access = VolumeAccess::kSampler3D,
                                                        .still_band_rays = flags.band_rays,
                                                        .still_band_ms = flags.band_ms}),
                   "renderer");
  f->still_minmax = BrickMinMaxCpu(volume, BrickVoxels(RenderQuality::kStill, volume.geometry()));
  f->interactive_minmax =
      BrickMinMaxCpu(volume, BrickVoxels(RenderQuality::kInteractive, volume.geometry()));
  if (!flags.render_tf.empty()) {
    f->custom = bench::Check(
        RenderPresetFromTf(bench::Check(ReadRenderTransferFunction(flags.render_tf), "--render-tf"),
                           volume),
        "--render-tf preset");
  }
  return f;
}

// The rows: every frame kind with and without skipping, then variants.
std::vector<Case> Cases(bool custom) {
  const auto kStill = RenderQuality::kStill, kInteractive = RenderQuality::kInteractive;
  const auto kDvr = RenderMode::kDvr, kMip = RenderMode::kMip;
  const auto kTexel = VolumeAccess::kTexelBuffer, kSampled = VolumeAccess::kSampler3D;
  std::vector<Case> cases;
  if (custom) {
    cases.push_back({"still DVR custom", kDvr, kCustomPreset, kStill, true});
    cases.push_back({"interactive DVR custom", kDvr, kCustomPreset, kInteractive, true});
  }
  for (bool skip : {true, false}) {
    const std::string s = skip ? "" : ", no skip";
    cases.push_back({"still DVR ct-vessels" + s, kDvr, "ct-vessels", kStill, skip});
    cases.push_back({"still DVR ct-soft-tissue" + s, kDvr, "ct-soft-tissue", kStill, skip});
    if (skip) cases.push_back({"still DVR ct-bone", kDvr, "ct-bone", kStill, true});
    cases.push_back({"still MIP" + s, kMip, "ct-vessels", kStill, skip});
    cases.push_back({"interactive DVR ct-vessels" + s, kDvr, "ct-vessels", kInteractive, skip});
    cases.push_back({"interactive MIP" + s, kMip, "ct-vessels", kInteractive, skip});
  }
  cases.push_back({"still DVR ct-vessels, no shading", kDvr, "ct-vessels", kStill, true, false});
  // Still frames with the central-difference taps (the default before the
  // cell gradient).
  for (const char* preset : {"ct-vessels", "ct-soft-tissue", "ct-bone"}) {
    cases.push_back({std::string("still DVR ") + preset + ", tap gradient", kDvr, preset, kStill,
                     true, true, true, kTexel, false});
  }
  // The drag loop's frame (drag_loop_bench): what shading costs there.
  cases.push_back({"interactive DVR ct-soft-tissue", kDvr, "ct-soft-tissue", kInteractive, true});
  cases.push_back({"interactive DVR ct-soft-tissue, no shading", kDvr, "ct-soft-tissue",
                   kInteractive, true, false});
  cases.push_back({"still DVR ct-vessels, map unchanged", kDvr, "ct-vessels", kStill, true});
  cases.push_back({"still DVR ct-vessels, no map", kDvr, "ct-vessels", kStill, true, true, false});
  cases.push_back({"still MIP, no map", kMip, "ct-vessels", kStill, true, true, false});
  cases.push_back({"still MIP, no map, in order", kMip, "ct-vessels", kStill, true, true, false,
                   kTexel, true, false});
  cases.push_back({"still MIP, no map, peak unrefined", kMip, "ct-vessels", kStill, true, true,
                   false, kTexel, true, true, false});
  cases.push_back({"interactive MIP, peak unrefined", kMip, "ct-vessels", kInteractive, true, true,
                   true, kTexel, true, true, false});
  cases.push_back({"still MIP, no skip, no map", kMip, "ct-vessels", kStill, false, true, false});
  cases.push_back(
      {"still DVR ct-vessels, sampler3D", kDvr, "ct-vessels", kStill, true, true, true, kSampled});
  cases.push_back({"still MIP, sampler3D", kMip, "ct-vessels", kStill, true, true, true, kSampled});
  return cases;
}

// The run's set-up and what a peer renderer needs to draw the same frames
// (bench/peer_vtk.py), then the table's header.
void PrintHeader(const Flags& flags, const Fixture& f, int reps) {
  const Volume& volume = f.volume;
  std::printf(
      "ray casting %s (%lldx%lldx%lld), device '%s'; min of %d, GPU and CPU (2 threads) "
      "alternating; identity map %ux%ux%u; renderer created in %.1f ms\n",
      flags.source.c_str(), (long long)volume.dims()[0], (long long)volume.dims()[1],
      (long long)volume.dims()[2], f.context->device_name().c_str(), reps, f.m, f.m, f.m,
      f.create_ms);
  const Camera camera = Camera::ForVolume(volume.geometry());
  const glm::dvec3 eye = camera.Eye(), target = camera.Target(), up = camera.Up();
  const MipWindow w = flags.window.value_or(VolumeMipWindow(volume));
  std::printf(
      "camera: eye_mm %.6f %.6f %.6f target_mm %.6f %.6f %.6f up %.6f %.6f %.6f "
      "fov_deg %.6f\n",
      eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z, camera.pose().fov_deg);
  std::printf(
      "mip window: width %.6f level %.6f; step: %s\n", w.width, w.level,
      flags.step_mm > 0.0 ? (std::to_string(flags.step_mm) + " mm").c_str() : "each quality's own");
  std::printf("%-36s %9s %7s %7s %7s %7s %7s | %7s %7s %7s | %8s %7s\n", "frame (as shown)",
              "cast", "GPU ms", "GPU all", "wall", "CPU ms", "CPU/GPU", "GPU t/2", "CPU t/2",
              "CPU/GPU", "err mean", "max/255");
}

// A row's request: the default camera, the flags' step, window and
// settings, the identity map unless the row or --no-map says otherwise.
RenderRequest CaseRequest(const Case& c, const Flags& flags, Fixture& f) {
  RenderRequest r;
  r.camera = Camera::ForVolume(f.volume.geometry());
  r.mode = c.mode;
  r.preset = c.preset == kCustomPreset
                 ? *f.custom
                 : bench::Check(MakeRenderPreset(c.preset, f.volume), "preset");
  r.quality = c.quality;
  r.width = r.height = flags.size;
  r.volume = &*f.gpu_volume;
  r.volume_image = f.volume_image;
  r.backward_map = c.map && !flags.no_map ? &*f.map : nullptr;
  // 0: the occupancy is recomputed every frame, as while dragging.
  r.backward_map_version =
      flags.map_held || c.name.find("map unchanged") != std::string::npos ? 1 : 0;
  r.mip_window = flags.window;
  if (flags.step_mm > 0.0) r.settings.step_mm = flags.step_mm;
  r.settings.empty_space_skipping = c.skipping;
  r.settings.early_termination = flags.early_termination;
  r.settings.light_both_ends = flags.light_both_ends;
  r.settings.partial_end_steps = flags.partial_end_steps;
  r.settings.shading = c.shading;
  r.settings.mip_brightest_first = c.brightest_first;
  r.settings.mip_peak_refine = c.peak_refine;
  r.settings.interactive_cell_gradient = r.settings.still_cell_gradient = c.cell_gradient;
  return r;
}

// A row's frame `reps` times, GPU and CPU reference alternating so that
// both see the same machine load; the minimum of each figure, and the
// reference's difference from the last GPU frame.
Measured MeasureCase(const Case& c, const RenderRequest& r, bool reference, Fixture& f,
                     VolumeRenderer& renderer, int reps) {
  Measured best;
  bench::Check(renderer.Render(r), "warm-up render");
  Frame cpu;
  for (int rep = 0; rep < reps; ++rep) {
    double c0 = ProcessCpuMs();
    Frame frame = bench::Check(renderer.Render(r), "render");
    best.gpu_cpu_time_ms = std::min(best.gpu_cpu_time_ms, (ProcessCpuMs() - c0) / 2.0);
    best.gpu_raycast_ms = std::min(best.gpu_raycast_ms, frame.timings.raycast_ms);
    best.gpu_total_ms = std::min(best.gpu_total_ms, frame.timings.render_ms);
    best.gpu_map_copy_ms = std::min(best.gpu_map_copy_ms, frame.timings.map_copy_ms);
    best.gpu_occupancy_ms = std::min(best.gpu_occupancy_ms, frame.timings.occupancy_ms);
    best.gpu_upscale_ms = std::min(best.gpu_upscale_ms, frame.timings.upscale_ms);
    best.wall_ms = std::min(best.wall_ms, frame.timings.wall_ms);
    best.frame = std::move(frame);
    if (!reference) continue;
    c0 = ProcessCpuMs();
    const auto& minmax = c.quality == RenderQuality::kStill ? f.still_minmax : f.interactive_minmax;
    cpu = bench::Check(
        RenderReference(r, f.volume, r.backward_map ? &f.host_map : nullptr, 2, &minmax),
        "reference");
    best.cpu_cpu_time_ms = std::min(best.cpu_cpu_time_ms, (ProcessCpuMs() - c0) / 2.0);
    best.cpu_ms = std::min(
        best.cpu_ms, cpu.timings.occupancy_ms + cpu.timings.raycast_ms + cpu.timings.upscale_ms);
  }
  if (!reference) best.mean_err = best.max_err = best.cpu_ms = best.cpu_cpu_time_ms = NAN;
  for (size_t i = 0; i < cpu.rgba.size(); ++i) {
    if (i % 4 == 3) continue;
    const double d = std::abs(double(cpu.rgba[i]) - double(best.frame.rgba[i]));
    best.mean_err += d / (cpu.rgba.size() * 0.75);
    best.max_err = std::max(best.max_err, d);
  }
  return best;
}

// A row's figures, then (one more frame, counting) the samples taken: the
// rate the cast achieved, against the machine's limit (docs/BENCHMARKS.md,
// "Ray casting").
void PrintCase(const Case& c, const Measured& best, const RenderRequest& r,
               VolumeRenderer& renderer) {
  std::printf("%-36s %4dx%-4d %7.1f %7.1f %7.1f %7.1f %7.2f | %7.1f %7.1f %7.2f | %8.3f %7.0f\n",
              c.name.c_str(), best.frame.render_width, best.frame.render_height,
              best.gpu_raycast_ms, best.gpu_total_ms, best.wall_ms, best.cpu_ms,
              best.cpu_ms / best.gpu_total_ms, best.gpu_cpu_time_ms, best.cpu_cpu_time_ms,
              best.cpu_cpu_time_ms / best.gpu_cpu_time_ms, best.mean_err, best.max_err);
  RenderRequest counting = r;
  counting.settings.count_samples = true;
  const Frame counted = bench::Check(renderer.Render(counting), "render");
  const double pixels = double(counted.render_width) * counted.render_height;
  std::printf(
      "%-36s GPU map copy %.1f, occupancy %.1f, upscale %.1f ms (min each); "
      "%.1f samples/pixel, %.0f M samples/s in the cast (%.0f M/s of CPU time); "
      "%d bands in %d submits\n",
      "", best.gpu_map_copy_ms, best.gpu_occupancy_ms, best.gpu_upscale_ms,
      double(counted.samples) / pixels, double(counted.samples) / best.gpu_raycast_ms * 1e-3,
      double(counted.samples) / best.gpu_cpu_time_ms * 1e-3, best.frame.bands, best.frame.submits);
}

// What the cell gradient costs in picture against the taps (central
// differences of J), GPU both, same request (RENDERING.md).
void CompareGradients(const Flags& flags, Fixture& f) {
  for (const char* quality : {"interactive", "still"}) {
    if (!Matches(std::string(quality) + " cell gradient", flags.filter)) continue;
    for (const char* preset : {"ct-soft-tissue", "ct-vessels", "ct-bone"}) {
      RenderRequest r;
      r.camera = Camera::ForVolume(f.volume.geometry());
      r.preset = bench::Check(MakeRenderPreset(preset, f.volume), "preset");
      r.quality = std::string(quality) == "still" ? RenderQuality::kStill
                                                  : RenderQuality::kInteractive;
      r.width = r.height = flags.size;
      r.volume = &*f.gpu_volume;
      r.backward_map = &*f.map;
      const Frame cell = bench::Check(f.texel_renderer->Render(r), "render");
      r.settings.interactive_cell_gradient = r.settings.still_cell_gradient = false;
      const Frame taps = bench::Check(f.texel_renderer->Render(r), "render");
      WritePng(flags.png_dir, std::string(quality) + "_cell_gradient_" + preset, cell);
      WritePng(flags.png_dir, std::string(quality) + "_tap_gradient_" + preset, taps);
      const Difference d = Compare(cell, taps);
      std::printf("%s %s, cell vs tap gradient: mean %.3f/255, max %.0f/255, "
                  "PSNR %.1f dB; cast %.1f vs %.1f ms\n",
                  quality, preset, d.mean, d.max, d.psnr_db, cell.timings.raycast_ms,
                  taps.timings.raycast_ms);
    }
  }
}

// One preset's still at `factor` x the smallest spacing against 0.5 x,
// GPU both, same request: picture difference, samples per pixel, cast time
// (min of `reps`, the two alternating).
void CompareStep(const Flags& flags, Fixture& f, const char* preset, double factor, bool oblique,
                 int reps) {
  const double smallest =
      std::min({f.volume.geometry().spacing_mm[0], f.volume.geometry().spacing_mm[1],
                f.volume.geometry().spacing_mm[2]});
  RenderRequest r;
  r.camera = Camera::ForVolume(f.volume.geometry());
  if (oblique) r.camera.Orbit(35.0, 20.0);
  r.mode = std::string(preset) == "mip" ? RenderMode::kMip : RenderMode::kDvr;
  r.preset = bench::Check(
      MakeRenderPreset(r.mode == RenderMode::kMip ? "ct-vessels" : preset, f.volume), "preset");
  r.width = r.height = flags.size;
  r.volume = &*f.gpu_volume;
  r.backward_map = &*f.map;
  r.settings.count_samples = true;
  r.settings.step_mm = 0.5 * smallest;
  RenderRequest larger = r;
  larger.settings.step_mm = factor * smallest;
  Frame base, other;
  double base_ms = 1e300, other_ms = 1e300;
  for (int rep = 0; rep < reps; ++rep) {
    base = bench::Check(f.texel_renderer->Render(r), "render");
    other = bench::Check(f.texel_renderer->Render(larger), "render");
    base_ms = std::min(base_ms, base.timings.raycast_ms);
    other_ms = std::min(other_ms, other.timings.raycast_ms);
  }
  const std::string section = oblique ? "still step oblique" : "still step";
  char tag[64];
  std::snprintf(tag, sizeof(tag), "%s_%.2f_%s", oblique ? "oblique_step" : "still_step", factor,
                preset);
  WritePng(flags.png_dir, tag, other);
  WritePng(flags.png_dir, std::string(oblique ? "oblique_step_0.50_" : "still_step_0.50_") + preset,
           base);
  const Difference d = Compare(other, base);
  const double pixels = double(r.width) * r.height;
  std::printf(
      "%s %.2f vs %.2f x spacing, %s: mean %.3f/255, max %.0f/255, "
      "PSNR %.1f dB; samples/pixel %.1f vs %.1f; cast %.1f vs %.1f ms\n",
      section.c_str(), factor, base.step_mm / smallest, preset, d.mean, d.max, d.psnr_db,
      double(other.samples) / pixels, double(base.samples) / pixels, other_ms, base_ms);
}

// Still frames at larger steps against step 0.5 x the smallest spacing
// (the still step of every preset and mode before RenderPreset's
// still_step_factor). "still step oblique": the same from WriteViews'
// oblique camera (azimuth 35, elevation 20), for the larger steps only.
void CompareSteps(const Flags& flags, Fixture& f, int reps) {
  for (const bool oblique : {false, true}) {
    if (!Matches(oblique ? "still step oblique" : "still step", flags.filter)) continue;
    const std::vector<double> factors = oblique ? std::vector<double>{1.0, 1.25, 1.5}
                                                : std::vector<double>{0.75, 1.0, 1.25, 1.5, 2.0};
    for (const char* preset : {"ct-soft-tissue", "ct-vessels", "ct-bone", "mip"}) {
      for (double factor : factors) CompareStep(flags, f, preset, factor, oblique, reps);
    }
  }
}

// JPEG (quality 85) and PNG encoding of a frame, min of `reps`.
void MeasureEncoding(const Frame& f, int reps) {
  std::vector<uint8_t> jpeg, png;
  const double jpeg_ms = bench::MinMs(reps, [&] {
    jpeg = bench::Check(EncodeJpeg(f.rgba, f.width, f.height, 85), "jpeg");
  });
  const double png_ms =
      bench::MinMs(reps, [&] { png = bench::Check(EncodePng(f.rgba, f.width, f.height), "png"); });
  std::printf("\nencoding the still DVR frame (%dx%d): JPEG q85 %.2f ms, %zu bytes; "
              "PNG %.2f ms, %zu bytes\n",
              f.width, f.height, jpeg_ms, jpeg.size(), png_ms, png.size());
}

}  // namespace

int main(int argc, char** argv) {
  const Flags flags = ParseFlags(argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows appear as they are measured
  const int reps = 5;
  const std::unique_ptr<Fixture> f = MakeFixture(flags);
  PrintHeader(flags, *f, reps);
  std::optional<Frame> still_frame;
  for (const Case& c : Cases(f->custom.has_value())) {
    if (!Matches(c.name, flags.filter)) continue;
    const RenderRequest r = CaseRequest(c, flags, *f);
    VolumeRenderer& renderer =
        c.access == VolumeAccess::kTexelBuffer ? *f->texel_renderer : *f->sampled_renderer;
    const Measured best = MeasureCase(c, r, flags.reference, *f, renderer, reps);
    PrintCase(c, best, r, renderer);
    std::string file = c.name;
    for (char& ch : file) ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
    WritePng(flags.png_dir, file, best.frame);
    if (c.name == "still DVR ct-vessels") still_frame = best.frame;
  }
  CompareGradients(flags, *f);
  CompareSteps(flags, *f, reps);
  if (!flags.png_dir.empty())
    WriteViews(flags.png_dir, f->volume, *f->gpu_volume, *f->texel_renderer);
  if (still_frame) MeasureEncoding(*still_frame, reps);
  return 0;
}

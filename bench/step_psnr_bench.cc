// How far each preset's still frame is from the same renderer at a finer
// step: PSNR (RGB, 8 bits) of the still at its own step against the still at
// step / FINE (default 8), per preset and volume, default camera (anterior,
// whole box), no map. The issue-29 floor is 40 dB.
// Usage: step_psnr_bench [--no-jitter] [--taps] [--no-preintegration]
//                        [--no-peak-refine] [--light-back-end]
//                        [--whole-end-steps] [--no-shading] [--cut]
//                        [--scale S]
//                        [--fine F] [--size N]
//                        [--png-dir DIR] [--presets A,B,...] SOURCE...
//   --no-jitter: ray starts not jittered (the renderer before jittering);
//   --taps: shade with central differences instead of the cell gradient;
//   --no-preintegration: each sample through the 1D table (a point);
//   --no-peak-refine: MIP of the samples alone (RaycastSettings::mip_peak_refine);
//   --light-back-end: pre-integrated steps lit by their back end's light
//   alone (RaycastSettings::light_both_ends off);
//   --whole-end-steps: a ray's first sample a whole step of its value and
//   nothing past its last (RaycastSettings::partial_end_steps off);
//   --scale S: the still at S x its own step (and the reference at S / F);
//   --no-shading: every preset unshaded;
//   --cut: the view cut through the orbit centre, facing the camera (what
//   the clients show first); --png-dir: writes VOLUME_PRESET_{still,fine}.png;
//   SOURCE: a volume file or phantom:NAME (default phantom:abdomen).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "server/io/read_volume.h"
#include "server/raycast/clip_region.h"
#include "server/raycast/frame_encoder.h"
#include "server/raycast/volume_renderer.h"

using namespace vpm;

namespace {

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t comma = s.find(',', start);
    const size_t end = comma == std::string::npos ? s.size() : comma;
    if (end > start) out.push_back(s.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::string FileStem(const std::string& source) {
  std::string stem = source.substr(source.find_last_of("/:") + 1);
  stem = stem.substr(0, stem.find('.'));
  return stem;
}

// The command line (see the usage above).
struct Options {
  bool jitter = true, cut = false, taps = false, shading = true, pre = true, refine = true,
       both_ends = true, partial_ends = true;
  double fine = 8.0, scale = 1.0;
  int size = 512;
  std::string png_dir;
  std::vector<std::string> presets = {"ct-soft-tissue", "ct-bone", "ct-vessels", "CT-AAA",
                                      "CT-Bone", "CT-Muscle", "CT-Chest-Contrast-Enhanced",
                                      "CT-Soft-Tissue", "mip"};
  std::vector<std::string> sources;
};

Options ParseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--no-jitter" || arg == "--no-shading" || arg == "--no-preintegration" ||
        arg == "--no-peak-refine" || arg == "--light-back-end" || arg == "--whole-end-steps" ||
        arg == "--taps" || arg == "--cut") {
      o.jitter &= arg != "--no-jitter";
      o.shading &= arg != "--no-shading";
      o.pre &= arg != "--no-preintegration";
      o.refine &= arg != "--no-peak-refine";
      o.both_ends &= arg != "--light-back-end";
      o.partial_ends &= arg != "--whole-end-steps";
      o.taps |= arg == "--taps";
      o.cut |= arg == "--cut";
    } else if (arg == "--scale" && i + 1 < argc) {
      o.scale = std::atof(argv[++i]);
    } else if (arg == "--fine" && i + 1 < argc) {
      o.fine = std::atof(argv[++i]);
    } else if (arg == "--size" && i + 1 < argc) {
      o.size = std::atoi(argv[++i]);
    } else if (arg == "--png-dir" && i + 1 < argc) {
      o.png_dir = argv[++i];
    } else if (arg == "--presets" && i + 1 < argc) {
      o.presets = Split(argv[++i]);
    } else {
      o.sources.push_back(arg);
    }
  }
  if (o.sources.empty()) o.sources.push_back("phantom:abdomen");
  return o;
}

// The still of preset `name` ("mip": MIP) as the options set it.
RenderRequest StillRequest(const Options& o, const std::string& name, const Volume& volume,
                           const GpuVolume& gpu_volume) {
  const VolumeGeometry& g = volume.geometry();
  RenderRequest r;
  r.camera = Camera::ForVolume(g);
  r.mode = name == "mip" ? RenderMode::kMip : RenderMode::kDvr;
  r.preset = bench::Check(MakeRenderPreset(name == "mip" ? "ct-vessels" : name, volume), "preset");
  r.quality = RenderQuality::kStill;
  r.width = r.height = o.size;
  r.volume = &gpu_volume;
  r.settings.jitter = o.jitter;
  r.settings.still_cell_gradient = !o.taps;
  r.settings.preintegrated = o.pre;
  r.settings.mip_peak_refine = o.refine;
  r.settings.light_both_ends = o.both_ends;
  r.settings.partial_end_steps = o.partial_ends;
  r.settings.shading = o.shading;
  if (!o.shading && r.preset.lighting) r.preset.lighting->shade = false;
  if (o.cut) {
    r.clip.planes.push_back(
        CutPlaneFacing(g.PhysicalToWorld(r.camera.Target()), g.direction * r.camera.Forward()));
  }
  if (o.scale != 1.0) r.settings.step_mm = RequestStepMm(r, g) * o.scale;
  return r;
}

// The still and its reference as PNG files, DIR/STEM_PRESET_still.png and
// _fine.png.
void WritePair(const std::string& base, const Frame& still, const Frame& reference) {
  for (auto [frame, suffix] :
       {std::pair{&still, "_still.png"}, std::pair{&reference, "_fine.png"}}) {
    const auto png = bench::Check(EncodePng(frame->rgba, frame->width, frame->height), "png");
    if (FILE* f = std::fopen((base + suffix).c_str(), "wb")) {
      std::fwrite(png.data(), 1, png.size(), f);
      std::fclose(f);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = ParseOptions(argc, argv);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  auto renderer = bench::Check(VolumeRenderer::Create(*context, {}), "renderer");
  std::printf(
      "still at its own step against step / %.0f, %dx%d, default camera%s, jitter %s, "
      "%s gradient, pre-integration %s (steps lit at %s, %s end steps), MIP peaks %s, "
      "shading %s\n",
      o.fine, o.size, o.size, o.cut ? ", view cut" : "", o.jitter ? "on" : "off",
      o.taps ? "tap" : "cell", o.pre ? "on" : "off", o.both_ends ? "both ends" : "the back end",
      o.partial_ends ? "partial" : "whole", o.refine ? "refined" : "as sampled",
      o.shading ? "as the preset" : "off");
  std::printf("%-24s %-28s %9s %9s %8s %8s\n", "volume", "preset", "step mm", "fine mm",
              "PSNR dB", "cast ms");
  double worst = 1e9;
  for (const std::string& source : o.sources) {
    const Volume volume = bench::Check(ReadVolume(source, {}), "reading the volume");
    const GpuVolume gpu_volume = bench::Check(GpuVolume::Upload(*context, volume), "upload");
    for (const std::string& name : o.presets) {
      RenderRequest r = StillRequest(o, name, volume, gpu_volume);
      const Frame still = bench::Check(renderer->Render(r), "still");
      r.settings.step_mm = still.step_mm / o.fine;
      const Frame reference = bench::Check(renderer->Render(r), "fine still");
      const double psnr = bench::PsnrOfMse(bench::RgbMse(still.rgba, reference.rgba));
      worst = std::min(worst, psnr);
      std::printf("%-24s %-28s %9.3f %9.4f %8.1f %8.1f\n", FileStem(source).c_str(), name.c_str(),
                  still.step_mm, reference.step_mm, psnr, still.timings.raycast_ms);
      if (!o.png_dir.empty()) {
        WritePair(o.png_dir + "/" + FileStem(source) + "_" + name, still, reference);
      }
    }
  }
  std::printf("lowest PSNR %.1f dB\n", worst);
  return 0;
}

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

}  // namespace

int main(int argc, char** argv) {
  bool jitter = true, cut = false, taps = false, shading = true, pre = true, refine = true,
       both_ends = true, partial_ends = true;
  double fine = 8.0, scale = 1.0;
  int size = 512;
  std::string png_dir;
  std::vector<std::string> presets = {"ct-soft-tissue", "ct-bone", "ct-vessels", "CT-AAA",
                                      "CT-Bone", "CT-Muscle", "CT-Chest-Contrast-Enhanced",
                                      "CT-Soft-Tissue", "mip"};
  std::vector<std::string> sources;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--no-jitter") {
      jitter = false;
    } else if (arg == "--no-shading") {
      shading = false;
    } else if (arg == "--no-preintegration") {
      pre = false;
    } else if (arg == "--no-peak-refine") {
      refine = false;
    } else if (arg == "--light-back-end") {
      both_ends = false;
    } else if (arg == "--whole-end-steps") {
      partial_ends = false;
    } else if (arg == "--taps") {
      taps = true;
    } else if (arg == "--cut") {
      cut = true;
    } else if (arg == "--scale" && i + 1 < argc) {
      scale = std::atof(argv[++i]);
    } else if (arg == "--fine" && i + 1 < argc) {
      fine = std::atof(argv[++i]);
    } else if (arg == "--size" && i + 1 < argc) {
      size = std::atoi(argv[++i]);
    } else if (arg == "--png-dir" && i + 1 < argc) {
      png_dir = argv[++i];
    } else if (arg == "--presets" && i + 1 < argc) {
      presets = Split(argv[++i]);
    } else {
      sources.push_back(arg);
    }
  }
  if (sources.empty()) sources.push_back("phantom:abdomen");
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  auto renderer = bench::Check(VolumeRenderer::Create(*context, {}), "renderer");
  std::printf("still at its own step against step / %.0f, %dx%d, default camera%s, jitter %s, "
              "%s gradient, pre-integration %s (steps lit at %s, %s end steps), MIP peaks %s, "
              "shading %s\n",
              fine, size, size, cut ? ", view cut" : "", jitter ? "on" : "off",
              taps ? "tap" : "cell", pre ? "on" : "off", both_ends ? "both ends" : "the back end",
              partial_ends ? "partial" : "whole",
              refine ? "refined" : "as sampled",
              shading ? "as the preset" : "off");
  std::printf("%-24s %-28s %9s %9s %8s %8s\n", "volume", "preset", "step mm", "fine mm",
              "PSNR dB", "cast ms");
  double worst = 1e9;
  for (const std::string& source : sources) {
    const Volume volume = bench::Check(ReadVolume(source, {}), "reading the volume");
    const GpuVolume gpu_volume = bench::Check(GpuVolume::Upload(*context, volume), "upload");
    const VolumeGeometry& g = volume.geometry();
    for (const std::string& name : presets) {
      RenderRequest r;
      r.camera = Camera::ForVolume(g);
      r.mode = name == "mip" ? RenderMode::kMip : RenderMode::kDvr;
      r.preset = bench::Check(MakeRenderPreset(name == "mip" ? "ct-vessels" : name, volume),
                              "preset");
      r.quality = RenderQuality::kStill;
      r.width = r.height = size;
      r.volume = &gpu_volume;
      r.settings.jitter = jitter;
      r.settings.still_cell_gradient = !taps;
      r.settings.preintegrated = pre;
      r.settings.mip_peak_refine = refine;
      r.settings.light_both_ends = both_ends;
      r.settings.partial_end_steps = partial_ends;
      r.settings.shading = shading;
      if (!shading && r.preset.lighting) r.preset.lighting->shade = false;
      if (cut) {
        r.clip.planes.push_back(CutPlaneFacing(g.PhysicalToWorld(r.camera.Target()),
                                               g.direction * r.camera.Forward()));
      }
      if (scale != 1.0) r.settings.step_mm = RequestStepMm(r, g) * scale;
      const Frame still = bench::Check(renderer->Render(r), "still");
      r.settings.step_mm = still.step_mm / fine;
      const Frame reference = bench::Check(renderer->Render(r), "fine still");
      const double psnr = bench::PsnrOfMse(bench::RgbMse(still.rgba, reference.rgba));
      worst = std::min(worst, psnr);
      std::printf("%-24s %-28s %9.3f %9.4f %8.1f %8.1f\n", FileStem(source).c_str(),
                  name.c_str(), still.step_mm, reference.step_mm, psnr,
                  still.timings.raycast_ms);
      if (!png_dir.empty()) {
        const std::string base = png_dir + "/" + FileStem(source) + "_" + name;
        for (auto [frame, suffix] : {std::pair{&still, "_still.png"},
                                     std::pair{&reference, "_fine.png"}}) {
          const auto png = bench::Check(EncodePng(frame->rgba, frame->width, frame->height),
                                        "png");
          if (FILE* f = std::fopen((base + suffix).c_str(), "wb")) {
            std::fwrite(png.data(), 1, png.size(), f);
            std::fclose(f);
          }
        }
      }
    }
  }
  std::printf("lowest PSNR %.1f dB\n", worst);
  return 0;
}

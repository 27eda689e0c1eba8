// What slices cost beside a 3D frame (RenderSettings.slices, RenderSlice):
// on a volume (default the 256^3 phantom) with its default mesh, the left
// renal artery grabbed and dragged 12 mm, the fastest of N runs of
//   - a still 3D frame (512 x 512, ct-soft-tissue) and its JPEG,
//   - each named slice through the dragged tissue (the slice kernel on the
//     GPU, the wall time of DeformableScene::RenderSlice with its readback
//     and window, and the JPEG of the slice),
// so a frame with three slices costs the first row plus the three others.
// Usage: slice_bench [SOURCE] [REPS] (a volume without the phantom's
// left_renal_artery landmark is grabbed at its centre)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>
#include <vector>

#include "bench/bench_util.h"
#include "server/io/read_volume.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/raycast/frame_encoder.h"
#include "server/scene/deformable_scene.h"

using namespace vpm;

namespace {

// The three slices through the grabbed tissue: each one's GPU, wall and
// JPEG ms, printed; returns their wall + JPEG ms summed.
double MeasureSlices(DeformableScene& scene, const Volume& volume, int reps) {
  const glm::dvec3 at = volume.geometry().PhysicalToWorld(*scene.GrabbedTissueMm());
  double slices_ms = 0.0;
  for (auto [name, orientation, at_mm] :
       {std::tuple{"axial slice", SliceOrientation::kAxial, at.z},
        std::tuple{"coronal slice", SliceOrientation::kCoronal, at.y},
        std::tuple{"sagittal slice", SliceOrientation::kSagittal, at.x}}) {
    SliceView slice_view;
    slice_view.plane = {.orientation = orientation, .at_mm = at_mm};
    SliceFrame slice;
    double gpu_ms = 1e300;
    const double wall_ms = bench::MinMs(reps, [&] {
      slice = bench::Check(scene.RenderSlice(slice_view), "slice");
      gpu_ms = std::min(gpu_ms, slice.gpu_ms);
    });
    const double jpeg_ms = bench::MinMs(reps, [&] {
      bench::Check(EncodeJpeg(slice.rgba, slice.grid.width, slice.grid.height, 85), "jpeg");
    });
    slices_ms += wall_ms + jpeg_ms;
    const std::string label = StrCat(name, " ", slice.grid.width, "x", slice.grid.height);
    std::printf("%-26s %10d %10.2f %10.1f %10.1f\n", label.c_str(),
                slice.grid.width * slice.grid.height, gpu_ms, wall_ms, jpeg_ms);
  }
  return slices_ms;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string source = argc > 1 ? argv[1] : "phantom:abdomen";
  const int reps = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  auto volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  auto gpu_volume = bench::Check(GpuVolume::Upload(*context, volume), "upload");
  auto renderer = bench::Check(VolumeRenderer::Create(*context, {}), "renderer");
  // The phantom's left renal artery; a volume without it: the centre.
  glm::dvec3 grab = 0.5 * volume.geometry().extent_mm();
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") grab = l.position_mm;
  }
  MeshParams params;
  params.refine_at_mm = grab;
  auto costs = bench::Check(LatticeCostsGpu::Create(*context), "kernel");
  auto mesh = bench::Check(BuildProxyMesh(volume, params, {&gpu_volume, &costs}), "mesh");
  DeformableScene::Options options;
  options.defer_map_update = true;  // as the server's sessions
  auto scene = bench::Check(
      DeformableScene::Create(*context, volume, gpu_volume, *renderer, mesh, options), "scene");
  bench::Check(scene->Grab(grab, mesh.stats.h_mm), "grab");
  bench::Check(scene->Drag(glm::dvec3(0.0, 0.0, 12.0)), "drag");
  // The drag at once exceeds the per-event bound: finish it (docs/FEM.md).
  bench::Check(scene->Settle(kSettleSolves), "settle");
  bench::Check(scene->SyncMap(), "map");
  const auto& d = volume.dims();
  std::printf(
      "slices: %s (%lld x %lld x %lld), %zu vertices, grab left_renal_artery dragged "
      "12 mm, device '%s', fastest of %d\n\n",
      source.c_str(), static_cast<long long>(d[0]), static_cast<long long>(d[1]),
      static_cast<long long>(d[2]), mesh.vertices.size(), context->device_name().c_str(), reps);
  std::printf("%-26s %10s %10s %10s %10s\n", "", "pixels", "GPU ms", "wall ms", "JPEG ms");

  SceneView view{.camera = Camera::ForVolume(volume.geometry()),
                 .preset = bench::Check(MakeRenderPreset("ct-soft-tissue", volume), "preset"),
                 .quality = RenderQuality::kStill,
                 .width = 512,
                 .height = 512};
  Frame frame;
  const double frame_ms =
      bench::MinMs(reps, [&] { frame = bench::Check(scene->Render(view), "frame"); });
  const double frame_jpeg_ms = bench::MinMs(
      reps, [&] { bench::Check(EncodeJpeg(frame.rgba, frame.width, frame.height, 85), "jpeg"); });
  std::printf("%-26s %10d %10s %10.1f %10.1f\n", "3D still frame 512x512", 512 * 512, "-", frame_ms,
              frame_jpeg_ms);
  const double slices_ms = MeasureSlices(*scene, volume, reps);
  std::printf("\nthree slices add %.1f ms to a %.1f ms frame (render + JPEG)\n", slices_ms,
              frame_ms + frame_jpeg_ms);
  return 0;
}

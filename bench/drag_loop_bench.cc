// The interactive loop on the phantom, per drag step: FEM solve, backward-map
// update, ray casting (interactive 256x256 and still 512x512), JPEG encode,
// and the frame rate of the whole interactive loop; for the 250-vertex mesh
// refined at the left renal artery, and for ~1,000 and ~5,000 vertices.
#include <cstdio>

#include "bench/bench_util.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/render/deformable_scene.h"
#include "server/render/frame_encoder.h"
#include "server/volume/read_volume.h"

using namespace vpm;

namespace {

struct Case {
  const char* name;
  std::array<int64_t, 3> grid;
  int64_t target;
};

struct Row {
  double fem = 1e300, map = 1e300, interactive = 1e300, still = 1e300, encode = 1e300;
  double loop_fps = 0.0;
  int64_t vertices = 0, inverted = 0;
};

Row RunCase(const Case& c, const Volume& volume, const gpu::GpuContext& context,
            GpuVolume& gpu_volume, VolumeRenderer& renderer, const glm::dvec3& grab) {
  MeshParams params;
  params.grid = c.grid;
  params.target = c.target;
  params.refine_at_mm = grab;
  auto costs = bench::Check(LatticeCostsGpu::Create(context), "kernel");
  auto mesh = bench::Check(BuildProxyMesh(volume, params, {&gpu_volume, &costs}), "mesh");
  auto scene = bench::Check(
      DeformableScene::Create(context, volume, gpu_volume, renderer, mesh, {}), "scene");
  bench::Check(scene->Grab(grab, mesh.stats.h_mm), "grab");
  SceneView interactive{.camera = Camera::ForVolume(volume.geometry()),
                        .preset = bench::Check(MakeRenderPreset("ct-soft-tissue", volume), "preset"),
                        .quality = RenderQuality::kInteractive,
                        .width = 256,
                        .height = 256};
  SceneView still = interactive;
  still.quality = RenderQuality::kStill;
  still.width = still.height = 512;
  Row row;
  row.vertices = static_cast<int64_t>(mesh.vertices.size());
  const int steps = 10;
  const auto t_loop = std::chrono::steady_clock::now();
  for (int s = 1; s <= steps; ++s) {
    // 12 mm cranially in 10 steps: the standard drag of docs/MESH.md.
    auto step = bench::Check(scene->Drag(glm::dvec3(0.0, 0.0, 1.2 * s)), "drag");
    row.fem = std::min(row.fem, step.fem_ms);
    row.map = std::min(row.map, step.warp_ms);
    row.inverted = step.inverted_tets;
    auto frame = bench::Check(scene->Render(interactive), "render");
    row.interactive = std::min(row.interactive, frame.timings.wall_ms);
    const auto t0 = std::chrono::steady_clock::now();
    auto jpeg = bench::Check(EncodeJpeg(frame.rgba, frame.width, frame.height, 85), "jpeg");
    row.encode = std::min(row.encode, bench::MsSince(t0));
  }
  row.loop_fps = steps / (bench::MsSince(t_loop) / 1000.0);
  for (int r = 0; r < 3; ++r) {
    auto frame = bench::Check(scene->Render(still), "still");
    row.still = std::min(row.still, frame.timings.wall_ms);
  }
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string source = argc > 1 ? argv[1] : "phantom:abdomen";
  auto volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  auto gpu_volume = bench::Check(GpuVolume::Upload(*context, volume), "upload");
  auto renderer = bench::Check(VolumeRenderer::Create(*context, {}), "renderer");
  glm::dvec3 grab(0.0);
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") grab = l.position_mm;
  }
  std::printf("drag loop: %s, grab left_renal_artery, drag 12 mm in 10 steps, device '%s'\n",
              source.c_str(), context->device_name().c_str());
  std::printf("per step, best of the 10 steps (ms); loop = FEM + map + interactive frame + JPEG\n");
  std::printf("%-22s %6s %8s %8s %13s %11s %8s %9s %9s\n", "mesh", "verts", "FEM", "map",
              "frame 256^2", "still 512^2", "JPEG", "loop fps", "inverted");
  for (const Case& c : {Case{"20^3 -> 250 + refine", {20, 20, 20}, 250},
                        Case{"24^3 -> 1000 + refine", {24, 24, 24}, 1000},
                        Case{"40^3 -> 5000 + refine", {40, 40, 40}, 5000}}) {
    const Row r = RunCase(c, volume, *context, gpu_volume, *renderer, grab);
    std::printf("%-22s %6lld %8.2f %8.2f %13.1f %11.1f %8.2f %9.1f %9lld\n", c.name,
                static_cast<long long>(r.vertices), r.fem, r.map, r.interactive, r.still,
                r.encode, r.loop_fps, static_cast<long long>(r.inverted));
  }
  return 0;
}

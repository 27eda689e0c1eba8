// Volume warping (docs/ALGORITHM.md section 7, docs/WARP.md) on the phantom
// (default 256^3) with its 250-vertex proxy mesh and a synthetic smooth drag
// at the liver landmark: backward-map updates (all tets, moved tets only) at
// the default map resolution and at full resolution, the full-volume warp
// through the map (source read by sampler or texel buffer), the CPU
// references on 2 threads, and the error of coarse maps against the exact
// (full-resolution) warp.
#include <algorithm>
#include <cmath>

#include <cstdio>
#include <optional>

#include "bench/bench_util.h"
#include "server/gpu/compute_batch.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/tet_quality.h"
#include "server/warp/backward_map.h"
#include "server/warp/backward_map_cpu.h"
#include "server/common/parallel_chunks.h"
#include "server/warp/warp_volume.h"
#include "server/warp/warp_volume_cpu.h"
#include "server/io/read_volume.h"

using namespace vpm;

namespace {

using Tets = std::vector<std::array<int32_t, 4>>;
using Positions = std::vector<glm::dvec3>;
using Dims = std::array<int64_t, 3>;

constexpr int kReps = 5;
constexpr int kCpuThreads = 2;

struct Scene {
  Volume volume;
  Positions rest;
  Positions half_drag;  // 90% of the drag, the frame before
  Positions drag;
  Tets tets;
};

// The drag: vertices within radius of the centre move by
// offset * (1 - r^2/radius^2)^2; anchors and hard (bone) vertices stay.
Positions Drag(const ProxyMesh& mesh, const glm::dvec3& centre, double radius,
               const glm::dvec3& offset) {
  Positions p;
  for (const MeshVertex& v : mesh.vertices) {
    const double q = glm::dot(v.position_mm - centre, v.position_mm - centre) / (radius * radius);
    const bool fixed = v.hard || v.kind == VertexKind::kAnchor || q >= 1.0;
    p.push_back(v.position_mm + (fixed ? glm::dvec3(0.0) : offset * (1.0 - q) * (1.0 - q)));
  }
  return p;
}

Scene MakeScene(const std::string& source) {
  Volume volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  glm::dvec3 centre = volume.geometry().extent_mm() * 0.5;
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "liver") centre = l.position_mm;
  }
  const ProxyMesh mesh = bench::Check(BuildProxyMesh(volume, MeshParams{}), "proxy mesh");
  // Up to 15 mm spread over 90 mm, scaled down until no tet inverts: next
  // to fixed bone vertices a synthetic drag folds tets sooner than FEM.
  const double radius = 90.0;
  glm::dvec3 offset(12.0, -4.0, 8.0);
  while (CountInvertedTets(Drag(mesh, centre, radius, offset), mesh.tets) > 0) offset *= 0.9;
  Scene scene{std::move(volume),
              {},
              Drag(mesh, centre, radius, 0.9 * offset),
              Drag(mesh, centre, radius, offset),
              mesh.tets};
  for (const MeshVertex& v : mesh.vertices) scene.rest.push_back(v.position_mm);
  int64_t moved = 0;
  for (size_t v = 0; v < scene.rest.size(); ++v) moved += scene.drag[v] != scene.rest[v];
  std::printf(
      "scene: %s (%lldx%lldx%lld), proxy mesh %zu vertices, %zu tets; drag at liver "
      "by |%.1f| mm, radius %.0f mm: %lld vertices move, %lld inverted tets\n",
      scene.volume.source().c_str(), (long long)scene.volume.dims()[0],
      (long long)scene.volume.dims()[1], (long long)scene.volume.dims()[2], scene.rest.size(),
      scene.tets.size(), glm::length(offset), radius, (long long)moved,
      (long long)CountInvertedTets(scene.drag, scene.tets));
  return scene;
}

struct UpdateTimes {
  double all_ms = 1e300, all_gpu_ms = 1e300, moved_ms = 1e300, moved_gpu_ms = 1e300;
  BackwardMap::UpdateStats moved_stats;
};

UpdateTimes TimeUpdates(BackwardMap& map, const Scene& s, int reps) {
  UpdateTimes t;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto stats = bench::Check(map.Rebuild(s.rest, s.drag, s.tets), "rebuild");
    t.all_ms = std::min(t.all_ms, MsSince(t0));
    t.all_gpu_ms = std::min(t.all_gpu_ms, stats.gpu_ms);
  }
  for (int r = 0; r < reps; ++r) {
    bench::Check(map.Update(s.rest, s.half_drag, s.tets), "update");
    const auto t0 = std::chrono::steady_clock::now();
    t.moved_stats = bench::Check(map.Update(s.rest, s.drag, s.tets), "update");
    t.moved_ms = std::min(t.moved_ms, MsSince(t0));
    t.moved_gpu_ms = std::min(t.moved_gpu_ms, t.moved_stats.gpu_ms);
  }
  return t;
}

void PrintUpdates(const UpdateTimes& t, const Dims& m, size_t tets) {
  const std::string map = StrCat("map ", m[0], "x", m[1], "x", m[2], " update");
  std::printf("%-52s %10.2f %10.2f\n", StrCat(map, ", all ", tets, " tets").c_str(), t.all_ms,
              t.all_gpu_ms);
  const auto& st = t.moved_stats;
  std::printf(
      "%-52s %10.2f %10.2f\n",
      StrCat(map, ", moved ", st.moved_tets, " (+", st.processed_tets - st.moved_tets, " meeting)")
          .c_str(),
      t.moved_ms, t.moved_gpu_ms);
  for (const auto& pass : st.passes) {
    std::printf("%-52s %10s %10.2f\n", StrCat("  of which ", pass.label).c_str(), "", pass.gpu_ms);
  }
  std::printf("%-52s %10.2f\n", "  of which copy into the image (GPU, same submit)", st.copy_ms);
}

// Wall (submit + wait) and kernel time of one warp into `out`.
std::pair<double, double> TimeWarp(const gpu::GpuContext& context, const VolumeWarper& warper,
                                   const GpuVolume& volume, const gpu::GpuImage3D* image,
                                   const BackwardMap& map, const gpu::GpuBuffer& out) {
  double wall = 1e300, kernel = 1e300;
  for (int r = 0; r < kReps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto batch = bench::Check(gpu::ComputeBatch::Begin(context, 1), "batch");
    if (!warper.Record(batch, volume, image, map, out).ok()) std::exit(1);
    auto timings = bench::Check(batch.SubmitAndWait(), "warp");
    wall = std::min(wall, MsSince(t0));
    kernel = std::min(kernel, timings.front().gpu_ms);
  }
  return {wall, kernel};
}

}  // namespace

namespace {

struct ErrorRow {
  double rmse_body_hu = 0, rmse_moved_hu = 0, max_hu = 0, max_mm = 0, rms_moved_mm = 0;
  double p99_mm = 0;  // 99th percentile over the moved voxels
};

// A coarse-map warp against the exact one: values over the body (exact
// J > -500 HU) and over the voxels that moved (|d| > 0.01 mm), and the
// displacement the coarse map gives at every voxel against the exact map.
ErrorRow CompareToExact(const Volume& coarse, const Volume& exact,
                        const BackwardMapValues& coarse_map, const BackwardMapValues& exact_map) {
  const VolumeGeometry& g = exact.geometry();
  struct Acc {
    double body2 = 0, moved2 = 0, max_hu = 0, max_mm = 0, mm2 = 0;
    int64_t body = 0;
    std::vector<float> moved_mm;
  };
  std::vector<Acc> per_slice(static_cast<size_t>(g.dims[2]));
  ParallelSlices(g.dims[2], kCpuThreads, [&](int64_t k) {
    Acc& a = per_slice[k];
    for (int64_t j = 0; j < g.dims[1]; ++j) {
      for (int64_t i = 0; i < g.dims[0]; ++i) {
        const int64_t n = exact.LinearIndex(i, j, k);
        const double e = double(coarse.voxels().floats()[n]) - exact.voxels().floats()[n];
        const glm::dvec3 d_exact(exact_map.values[n]);
        const glm::dvec3 d_coarse(coarse_map.Sample(g.IndexToPhysical(glm::dvec3(i, j, k))));
        const double mm = glm::length(d_coarse - d_exact);
        a.max_hu = std::max(a.max_hu, std::abs(e));
        a.max_mm = std::max(a.max_mm, mm);
        if (exact.voxels().floats()[n] > -500.0f) a.body2 += e * e, ++a.body;
        if (glm::length(d_exact) > 0.01) {
          a.moved2 += e * e, a.mm2 += mm * mm;
          a.moved_mm.push_back(float(mm));
        }
      }
    }
  });
  Acc t;
  for (const Acc& a : per_slice) {
    t.body2 += a.body2, t.moved2 += a.moved2, t.mm2 += a.mm2, t.body += a.body;
    t.max_hu = std::max(t.max_hu, a.max_hu);
    t.max_mm = std::max(t.max_mm, a.max_mm);
    t.moved_mm.insert(t.moved_mm.end(), a.moved_mm.begin(), a.moved_mm.end());
  }
  const double moved = std::max<double>(double(t.moved_mm.size()), 1.0);
  ErrorRow row{std::sqrt(t.body2 / std::max<int64_t>(t.body, 1)), std::sqrt(t.moved2 / moved),
               t.max_hu, t.max_mm, std::sqrt(t.mm2 / moved)};
  if (!t.moved_mm.empty()) {
    auto p99 = t.moved_mm.begin() + static_cast<int64_t>(0.99 * double(t.moved_mm.size() - 1));
    std::nth_element(t.moved_mm.begin(), p99, t.moved_mm.end());
    row.p99_mm = *p99;
  }
  return row;
}

double MaxAbsDiff(std::span<const float> a, std::span<const float> b) {
  double m = 0;
  for (size_t n = 0; n < a.size(); ++n) m = std::max(m, double(std::abs(a[n] - b[n])));
  return m;
}

// Voxels differing by more than 1 HU, and how many of them lie on a face of
// the volume (where the box-face vertices slide).
std::pair<int64_t, int64_t> CountOver1Hu(const Volume& a, const Volume& b) {
  const auto& d = a.dims();
  int64_t over = 0, on_face = 0;
  for (int64_t k = 0; k < d[2]; ++k)
    for (int64_t j = 0; j < d[1]; ++j)
      for (int64_t i = 0; i < d[0]; ++i) {
        const int64_t n = a.LinearIndex(i, j, k);
        if (std::abs(a.voxels().floats()[n] - b.voxels().floats()[n]) <= 1.0f) continue;
        ++over;
        if (i == 0 || j == 0 || k == 0 || i == d[0] - 1 || j == d[1] - 1 || k == d[2] - 1) {
          ++on_face;
        }
      }
  return {over, on_face};
}

// The CPU map and warps (2 threads) timed, and the GPU's warps through the
// coarse and exact maps against them.
void CompareWithCpu(const Scene& s, const Dims& coarse_dims, const Volume& warped_coarse,
                    const Volume& warped_exact) {
  const VolumeGeometry& g = s.volume.geometry();
  std::optional<BackwardMapValues> cpu_map;
  const double cpu_coarse_ms = bench::MinMs(3, [&] {
    cpu_map =
        bench::Check(BackwardMapCpu(g.extent_mm(), coarse_dims, s.rest, s.drag, s.tets), "cpu map");
  });
  std::printf("%-52s %10.2f\n", "CPU map, coarse (2 threads)", cpu_coarse_ms);
  const double cpu_full_ms = bench::MinMs(1, [&] {
    bench::Check(BackwardMapCpu(g.extent_mm(), g.dims, s.rest, s.drag, s.tets), "cpu map");
  });
  std::printf("%-52s %10.2f\n", "CPU map, full resolution (2 threads)", cpu_full_ms);
  std::optional<Volume> cpu_warp, cpu_exact;
  const double cpu_warp_ms = bench::MinMs(1, [&] {
    cpu_warp = bench::Check(WarpVolumeCpu(s.volume, *cpu_map, kCpuThreads), "cpu warp");
  });
  std::printf("%-52s %10.2f\n", "CPU warp through coarse map (2 threads)", cpu_warp_ms);
  const double cpu_exact_ms = bench::MinMs(1, [&] {
    cpu_exact = bench::Check(WarpVolumeExactCpu(s.volume, s.rest, s.drag, s.tets), "cpu exact");
  });
  std::printf("%-52s %10.2f\n", "CPU exact warp (2 threads)", cpu_exact_ms);
  std::printf("GPU vs CPU max |J| difference: coarse %.4f HU, exact %.4f HU\n",
              MaxAbsDiff(warped_coarse.voxels().floats(), cpu_warp->voxels().floats()),
              MaxAbsDiff(warped_exact.voxels().floats(), cpu_exact->voxels().floats()));
  for (const auto& [name, gpu, cpu] :
       {std::tuple{"coarse", &warped_coarse, &*cpu_warp}, {"exact", &warped_exact, &*cpu_exact}}) {
    const auto [over, on_face] = CountOver1Hu(*gpu, *cpu);
    std::printf("GPU vs CPU, %s: %lld voxels differ by more than 1 HU, %lld of them on the "
                "volume's faces\n", name, (long long)over, (long long)on_face);
  }
}

// The coarse maps (1/8, 1/4, 1/2 of the voxels per axis) against the exact
// warp: errors in HU and mm.
void PrintMapErrors(const gpu::GpuContext& context, const Scene& s, VolumeWarper& warper,
                    GpuVolume& gpu_volume, const Volume& warped_exact,
                    const BackwardMapValues& exact_values) {
  const VolumeGeometry& g = s.volume.geometry();
  std::printf("\ncoarse map vs exact warp (body: exact J > -500 HU; moved: |d| > 0.01 mm)\n");
  std::printf("%-14s %10s %11s %8s %8s %13s %11s\n", "map", "RMSE body", "RMSE moved", "max HU",
              "max mm", "P99 mm moved", "RMS mm moved");
  for (int64_t divisor : {8, 4, 2}) {
    Dims m;
    for (int a = 0; a < 3; ++a) m[a] = std::max<int64_t>((g.dims[a] + divisor - 1) / divisor, 2);
    auto map = bench::Check(BackwardMap::Create(context, g, {.map_dims = m}), "map");
    bench::Check(map.Update(s.rest, s.drag, s.tets), "update");
    const Volume j = bench::Check(warper.Warp(gpu_volume, s.volume, map), "warp");
    const ErrorRow e =
        CompareToExact(j, warped_exact, bench::Check(map.Download(), "download"), exact_values);
    std::printf("%-14s %10.3f %11.3f %8.1f %8.3f %13.3f %11.3f\n",
                StrCat(m[0], "x", m[1], "x", m[2]).c_str(), e.rmse_body_hu, e.rmse_moved_hu,
                e.max_hu, e.max_mm, e.p99_mm, e.rms_moved_mm);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const Scene s = MakeScene(argc > 1 ? argv[1] : "phantom:abdomen");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  const VolumeGeometry& g = s.volume.geometry();
  const Dims coarse_dims = DefaultBackwardMapDims(g.dims);
  auto coarse = bench::Check(BackwardMap::Create(*context, g), "coarse map");
  auto exact = bench::Check(BackwardMap::Create(*context, g, {.map_dims = g.dims}), "exact map");

  std::printf("\ndevice '%s', min of %d (full resolution: 3)\n", context->device_name().c_str(),
              kReps);
  std::printf("%-52s %10s %10s\n", "stage", "wall ms", "GPU ms");
  PrintUpdates(TimeUpdates(coarse, s, kReps), coarse_dims, s.tets.size());
  PrintUpdates(TimeUpdates(exact, s, 3), g.dims, s.tets.size());

  auto gpu_volume = bench::Check(GpuVolume::Upload(*context, s.volume), "upload");
  const gpu::GpuImage3D* image = bench::Check(gpu_volume.Image(*context, s.volume), "image");
  auto out = bench::Check(gpu::GpuBuffer::Create(*context, s.volume.voxels().floats().size() * 4,
                                                 vk::BufferUsageFlagBits::eStorageBuffer),
                          "out");
  auto by_texel = bench::Check(VolumeWarper::Create(*context), "warper");
  auto by_sampler = bench::Check(
      VolumeWarper::Create(*context, {.source_read = VolumeWarper::SourceRead::kSampler}),
      "warper");
  for (const auto* map : {&coarse, &exact}) {
    for (const auto* w : {&by_sampler, &by_texel}) {
      const auto [wall, kernel] = TimeWarp(*context, *w, gpu_volume, image, *map, out);
      std::printf("%-52s %10.2f %10.2f\n",
                  StrCat("warp ", g.dims[0], "^3 through ", map == &coarse ? "coarse" : "exact",
                         " map, source by ", w == &by_sampler ? "sampler" : "texel buffer")
                      .c_str(),
                  wall, kernel);
    }
  }
  const Volume warped_coarse = bench::Check(by_texel.Warp(gpu_volume, s.volume, coarse), "warp");
  const Volume warped_exact = bench::Check(by_texel.Warp(gpu_volume, s.volume, exact), "warp");
  const BackwardMapValues exact_values = bench::Check(exact.Download(), "download");

  CompareWithCpu(s, coarse_dims, warped_coarse, warped_exact);
  PrintMapErrors(*context, s, by_texel, gpu_volume, warped_exact, exact_values);
  return 0;
}

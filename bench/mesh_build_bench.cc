// Proxy-mesh build on the phantom (default 256^3, 20^3 lattice to 250
// vertices): each stage in ms and the whole build; then the scaling of step 2
// (fast O(N log N) removal vs the naive O(N^2) scan) on lattices of 8,000 to
// 1,000,000 vertices decimated to 3%.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "bench/bench_util.h"
#include "server/mesh/build_proxy_mesh.h"
#include "server/mesh/decimate.h"
#include "server/io/read_volume.h"

using namespace vpm;

namespace {

void StageTable(const Volume& volume, const gpu::GpuContext& context, const GpuVolume& gpu_volume,
                const LatticeCostsGpu& costs_gpu, double upload_ms) {
  MeshParams params;
  for (const Landmark& l : volume.landmarks()) {
    if (l.name == "left_renal_artery") params.refine_at_mm = l.position_mm;
  }
  const int reps = 5;
  MeshStats best;
  best.total_ms = 1e300;
  std::vector<MeshStats> runs;
  ProxyMesh mesh;
  for (int r = 0; r < reps; ++r) {
    mesh = bench::Check(BuildProxyMesh(volume, params, {&gpu_volume, &costs_gpu}), "build");
    runs.push_back(mesh.stats);
  }
  auto min_of = [&](double MeshStats::*field) {
    double m = 1e300;
    for (const auto& s : runs) m = std::min(m, s.*field);
    return m;
  };
  MeshParams cpu_params = params;
  double cpu_eval_ms = 1e300;
  for (int r = 0; r < 3; ++r) {
    auto m = bench::Check(BuildProxyMesh(volume, cpu_params), "cpu build");
    cpu_eval_ms = std::min(cpu_eval_ms, m.stats.evaluate_ms);
  }
  std::printf("\nmesh build: %s, 20^3 lattice -> 250 (+%lld refined at left_renal_artery), "
              "device '%s', min of %d\n",
              volume.source().c_str(), (long long)mesh.stats.refined,
              context.device_name().c_str(), reps);
  std::printf("%-32s %10s\n", "stage", "ms");
  std::printf("%-32s %10.2f\n", "upload volume (once per volume)", upload_ms);
  std::printf("%-32s %10.2f\n", "evaluate (step 1, GPU)", min_of(&MeshStats::evaluate_ms));
  std::printf("%-32s %10.2f\n", "evaluate (step 1, CPU reference)", cpu_eval_ms);
  std::printf("%-32s %10.2f\n", "decimate (step 2)", min_of(&MeshStats::decimate_ms));
  std::printf("%-32s %10.2f\n", "refine (step 4)", min_of(&MeshStats::refine_ms));
  std::printf("%-32s %10.2f\n", "classify (step 3)", min_of(&MeshStats::classify_ms));
  std::printf("%-32s %10.2f\n", "boundary vertices", min_of(&MeshStats::boundary_ms));
  std::printf("%-32s %10.2f\n", "tetrahedralize", min_of(&MeshStats::tetrahedralize_ms));
  std::printf("%-32s %10.2f\n", "Steiner points (rounds)", min_of(&MeshStats::steiner_ms));
  std::printf("%-32s %10.2f\n", "whole build (GPU step 1)", min_of(&MeshStats::total_ms));
  std::printf("vertices %zu (%lld Steiner), tets %zu, hard %lld, min dihedral %.2f deg\n",
              mesh.vertices.size(), (long long)mesh.stats.steiner, mesh.tets.size(),
              (long long)mesh.stats.hard, mesh.quality.min_dihedral_deg);
}

// FNV-1a over a decimation's removal order, kept set, kept costs (bits) and
// D0 (bits): equal hashes mean identical results.
uint64_t ResultHash(const DecimationResult& r) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&](uint64_t x) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((x >> (8 * b)) & 0xff)) * 1099511628211ull;
  };
  auto bits = [](double d) {
    uint64_t u;
    std::memcpy(&u, &d, sizeof u);
    return u;
  };
  for (int64_t v : r.removal_order) mix(static_cast<uint64_t>(v));
  for (int64_t v : r.kept) mix(static_cast<uint64_t>(v));
  for (double c : r.kept_cost) mix(bits(c));
  mix(bits(r.d0));
  return h;
}

void ScalingTable(const Volume& volume, const GpuVolume& gpu_volume,
                  const LatticeCostsGpu& costs_gpu, bool naive, bool hash) {
  std::printf("\nstep 2 scaling: decimate to 3%% of N (spread, cell footprint)\n");
  std::printf("%10s %12s %14s %10s %18s\n", "N", "fast ms", "naive ms", "naive/fast",
              "fast/(N log N) rel");
  double first_norm = 0.0, naive_per_n2 = 0.0;
  for (int64_t g : {20, 40, 64, 100}) {
    auto lattice = bench::Check(Lattice::Create(volume.geometry(), {g, g, g}), "lattice");
    const auto tf = TransferFunction::CtSoftTissue();
    auto costs = bench::Check(costs_gpu.Evaluate(gpu_volume, lattice, tf), "evaluate");
    DecimationInput in{.ci = costs.ci_cell, .cg = NormalizeGradientCost(costs.g_cell)};
    for (int64_t id = 0; id < lattice.size(); ++id) in.positions.push_back(lattice.Position(id));
    const int64_t n = lattice.size();
    const DecimationParams p{.target = n * 3 / 100 + kAnchorCount,
                             .radius_mm = 2.0 * lattice.h_mm()};
    const double fast_ms = bench::MinMs(3, [&] { bench::Check(DecimateFast(in, p), "fast"); });
    if (hash) {
      for (DensityMode mode : {DensityMode::kSpread, DensityMode::kPaper}) {
        DecimationParams q = p;
        q.density_mode = mode;
        const auto r = bench::Check(DecimateFast(in, q), "fast");
        std::printf("%10lld hash %-6s %016llx\n", (long long)n, DensityModeName(mode),
                    (unsigned long long)ResultHash(r));
      }
    }
    const double nlogn = double(n) * std::log2(double(n));
    if (first_norm == 0.0) first_norm = fast_ms / nlogn;
    // The naive scan runs only where its predicted time is under a minute.
    double naive_ms = -1.0;
    const double predicted_ms = naive_per_n2 * double(n) * double(n);
    if (naive && (naive_per_n2 == 0.0 || predicted_ms < 60'000.0)) {
      naive_ms = bench::MinMs(1, [&] { bench::Check(DecimateNaive(in, p), "naive"); });
      naive_per_n2 = naive_ms / (double(n) * double(n));
    }
    if (naive_ms >= 0) {
      std::printf("%10lld %12.1f %14.1f %10.1f %18.2f\n", (long long)n, fast_ms, naive_ms,
                  naive_ms / fast_ms, fast_ms / nlogn / first_norm);
    } else if (!naive) {
      std::printf("%10lld %12.1f %14s %10s %18.2f\n", (long long)n, fast_ms, "-", "-",
                  fast_ms / nlogn / first_norm);
    } else {
      std::printf("%10lld %12.1f %14s %10s %18.2f   (naive predicted %.0f s: skipped)\n",
                  (long long)n, fast_ms, "-", "-", fast_ms / nlogn / first_norm,
                  predicted_ms / 1000.0);
    }
  }
}

}  // namespace

// Usage: mesh_build_bench [SOURCE] [--stages-only | --scaling-only] [--no-naive] [--hash]
// --hash prints, per scaling size, a hash of step 2's result (removal order,
// kept set and costs, D0) in spread and paper mode, to check that a change
// to DecimateFast leaves its results identical.
int main(int argc, char** argv) {
  std::string source = "phantom:abdomen";
  bool stages = true, scaling = true, naive = true, hash = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--stages-only") {
      scaling = false;
    } else if (std::string(argv[i]) == "--scaling-only") {
      stages = false;
    } else if (std::string(argv[i]) == "--no-naive") {
      naive = false;
    } else if (std::string(argv[i]) == "--hash") {
      hash = true;
    } else {
      source = argv[i];
    }
  }
  auto volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  std::optional<GpuVolume> gpu_volume;
  const double upload_ms = bench::MinMs(3, [&] {
    gpu_volume.emplace(bench::Check(GpuVolume::Upload(*context, volume), "upload"));
  });
  auto costs_gpu = bench::Check(LatticeCostsGpu::Create(*context), "pipeline");
  if (stages) StageTable(volume, *context, *gpu_volume, costs_gpu, upload_ms);
  if (scaling) ScalingTable(volume, *gpu_volume, costs_gpu, naive, hash);
  return 0;
}

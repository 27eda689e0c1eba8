// What the machine can do for a ray caster, measured without lavapipe: the
// rate of trilinear samples (8 voxel reads, 7 lerps, the max of MIP) that a
// hand-vectorised loop (AVX2 gathers, 8 rays per vector, rays of a 4x2 pixel
// block as vpm's ray caster groups them) reaches on every core, along the
// rays of render_bench's default camera at 1 mm with no skipping; and the
// memory bandwidth of a streaming read. The ray caster's sample rates
// (render_bench prints them per frame) are compared with these figures in
// docs/BENCHMARKS.md ("How close to the machine").
// Usage: sample_rate_bench [SOURCE] [SIZE]  (phantom:abdomen, 512)
#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_util.h"
#include "server/io/read_volume.h"
#include "server/raycast/camera.h"

using namespace vpm;

namespace {

struct Rays {
  int width = 0, height = 0;
  std::vector<glm::vec3> dir;      // unit, per pixel
  std::vector<float> t_near, t_far;  // box interval per pixel (t_near > t_far: none)
  glm::vec3 eye{0.0f};
};

Rays MakeRays(const Volume& volume, int size) {
  const CameraRays cam = Camera::ForVolume(volume.geometry()).Rays(size, size);
  const glm::vec3 extent(volume.geometry().extent_mm());
  Rays r;
  r.width = r.height = size;
  r.eye = glm::vec3(cam.eye_mm);
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      const glm::vec3 d(cam.Direction(x, y));
      glm::vec3 inv;
      for (int a = 0; a < 3; ++a) inv[a] = 1.0f / (std::abs(d[a]) < 1e-20f ? 1e-20f : d[a]);
      const glm::vec3 ta = -r.eye * inv, tb = (extent - r.eye) * inv;
      const glm::vec3 lo = glm::min(ta, tb), hi = glm::max(ta, tb);
      r.dir.push_back(d);
      r.t_near.push_back(std::max({lo.x, lo.y, lo.z, 0.0f}));
      r.t_far.push_back(std::min({hi.x, hi.y, hi.z}));
    }
  }
  return r;
}

// MIP of 8 rays (lanes) at once: every sample a trilinear read of 8 voxels
// by 8 gathers. Returns the samples taken.
__attribute__((target("avx2,fma"))) int64_t MipBlock(const float* v, const int* dims,
                                                      const glm::vec3& inv_spacing,
                                                      const Rays& rays, const int* pixel,
                                                      float step, float* out) {
  alignas(32) float ex[8], ey[8], ez[8], dx[8], dy[8], dz[8], tn[8], tf[8];
  int steps = 0;
  for (int l = 0; l < 8; ++l) {
    const int p = pixel[l];
    ex[l] = rays.eye.x * inv_spacing.x;
    ey[l] = rays.eye.y * inv_spacing.y;
    ez[l] = rays.eye.z * inv_spacing.z;
    dx[l] = rays.dir[p].x * inv_spacing.x;
    dy[l] = rays.dir[p].y * inv_spacing.y;
    dz[l] = rays.dir[p].z * inv_spacing.z;
    tn[l] = rays.t_near[p];
    tf[l] = rays.t_far[p];
    if (tf[l] >= tn[l]) steps = std::max(steps, int((tf[l] - tn[l]) / step) + 1);
  }
  const __m256 vex = _mm256_load_ps(ex), vey = _mm256_load_ps(ey), vez = _mm256_load_ps(ez);
  const __m256 vdx = _mm256_load_ps(dx), vdy = _mm256_load_ps(dy), vdz = _mm256_load_ps(dz);
  const __m256 vtn = _mm256_load_ps(tn), vtf = _mm256_load_ps(tf);
  const __m256 zero = _mm256_setzero_ps();
  const __m256 lastx = _mm256_set1_ps(float(dims[0] - 1)), lasty = _mm256_set1_ps(float(dims[1] - 1)),
               lastz = _mm256_set1_ps(float(dims[2] - 1));
  const __m256i mx = _mm256_set1_epi32(dims[0] - 2), my = _mm256_set1_epi32(dims[1] - 2),
                mz = _mm256_set1_epi32(dims[2] - 2);
  const __m256i sy = _mm256_set1_epi32(dims[0]), sz = _mm256_set1_epi32(dims[0] * dims[1]);
  const __m256i one = _mm256_set1_epi32(1);
  __m256 best = _mm256_set1_ps(-3.0e38f);
  int64_t taken = 0;
  for (int k = 0; k < steps; ++k) {
    const __m256 t = _mm256_add_ps(vtn, _mm256_set1_ps(float(k) * step));
    const __m256 live = _mm256_cmp_ps(t, vtf, _CMP_LE_OQ);
    const int live_mask = _mm256_movemask_ps(live);
    if (live_mask == 0) break;
    taken += __builtin_popcount(unsigned(live_mask));
    const __m256 ux = _mm256_min_ps(_mm256_max_ps(_mm256_fmadd_ps(t, vdx, vex), zero), lastx);
    const __m256 uy = _mm256_min_ps(_mm256_max_ps(_mm256_fmadd_ps(t, vdy, vey), zero), lasty);
    const __m256 uz = _mm256_min_ps(_mm256_max_ps(_mm256_fmadd_ps(t, vdz, vez), zero), lastz);
    const __m256i ix = _mm256_min_epi32(_mm256_cvttps_epi32(ux), mx);
    const __m256i iy = _mm256_min_epi32(_mm256_cvttps_epi32(uy), my);
    const __m256i iz = _mm256_min_epi32(_mm256_cvttps_epi32(uz), mz);
    const __m256 fx = _mm256_sub_ps(ux, _mm256_cvtepi32_ps(ix));
    const __m256 fy = _mm256_sub_ps(uy, _mm256_cvtepi32_ps(iy));
    const __m256 fz = _mm256_sub_ps(uz, _mm256_cvtepi32_ps(iz));
    const __m256i base = _mm256_add_epi32(
        ix, _mm256_add_epi32(_mm256_mullo_epi32(iy, sy), _mm256_mullo_epi32(iz, sz)));
#define VPM_AT(offset) _mm256_i32gather_ps(v, _mm256_add_epi32(base, offset), 4)
#define VPM_LERP(a, b, f) _mm256_fmadd_ps(_mm256_sub_ps(b, a), f, a)
    const __m256i oy = sy, oz = sz, oyz = _mm256_add_epi32(sy, sz);
    const __m256 c000 = VPM_AT(_mm256_setzero_si256()), c100 = VPM_AT(one);
    const __m256 c010 = VPM_AT(oy), c110 = VPM_AT(_mm256_add_epi32(oy, one));
    const __m256 c001 = VPM_AT(oz), c101 = VPM_AT(_mm256_add_epi32(oz, one));
    const __m256 c011 = VPM_AT(oyz), c111 = VPM_AT(_mm256_add_epi32(oyz, one));
    const __m256 c00 = VPM_LERP(c000, c100, fx), c10 = VPM_LERP(c010, c110, fx);
    const __m256 c01 = VPM_LERP(c001, c101, fx), c11 = VPM_LERP(c011, c111, fx);
    const __m256 value = VPM_LERP(VPM_LERP(c00, c10, fy), VPM_LERP(c01, c11, fy), fz);
#undef VPM_AT
#undef VPM_LERP
    best = _mm256_blendv_ps(best, _mm256_max_ps(best, value), live);
  }
  _mm256_storeu_ps(out, best);
  return taken;
}

// Sum of n 32-bit words (n a multiple of 32), four AVX2 accumulators: a read
// limited by memory, not by the adds.
__attribute__((target("avx2"))) uint32_t SumWords(const uint32_t* p, size_t n) {
  __m256i a = _mm256_setzero_si256(), b = a, c = a, d = a;
  for (size_t i = 0; i < n; i += 32) {
    a = _mm256_add_epi32(a, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i)));
    b = _mm256_add_epi32(b, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i + 8)));
    c = _mm256_add_epi32(c, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i + 16)));
    d = _mm256_add_epi32(d, _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + i + 24)));
  }
  alignas(32) uint32_t out[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(out),
                     _mm256_add_epi32(_mm256_add_epi32(a, b), _mm256_add_epi32(c, d)));
  uint32_t sum = 0;
  for (uint32_t v : out) sum += v;
  return sum;
}

double ProcessCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

// Minimum over reps of wall ms and of process CPU ms / threads.
template <typename Fn>
std::pair<double, double> Measure(int reps, int threads, Fn fn) {
  double wall = 1e300, cpu = 1e300;
  for (int r = 0; r < reps; ++r) {
    const double c0 = ProcessCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    fn();
    wall = std::min(wall, MsSince(t0));
    cpu = std::min(cpu, (ProcessCpuMs() - c0) / threads);
  }
  return {wall, cpu};
}

// The MIP of every pixel on `threads` threads, in blocks of 4x2 pixels
// that the threads take from a shared counter; returns the samples taken.
int64_t CastMip(const Volume& volume, const Rays& rays, int size, int threads,
                std::vector<float>& image) {
  const int dims[3] = {int(volume.dims()[0]), int(volume.dims()[1]), int(volume.dims()[2])};
  const glm::vec3 inv_spacing = 1.0f / glm::vec3(volume.geometry().spacing_mm);
  const float step = 1.0f;
  const int blocks_x = size / 4, blocks_y = size / 2;
  std::atomic<int> next{0};
  std::atomic<int64_t> samples{0};
  auto worker = [&] {
    int64_t taken = 0;
    for (int b; (b = next.fetch_add(16)) < blocks_x * blocks_y;) {
      for (int i = b; i < std::min(b + 16, blocks_x * blocks_y); ++i) {
        const int bx = i % blocks_x, by = i / blocks_x;
        int pixel[8];
        for (int l = 0; l < 8; ++l) pixel[l] = (by * 2 + l / 4) * size + bx * 4 + l % 4;
        float out[8];
        taken +=
            MipBlock(volume.voxels().floats().data(), dims, inv_spacing, rays, pixel, step, out);
        for (int l = 0; l < 8; ++l) image[pixel[l]] = out[l];
      }
    }
    samples += taken;
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  return samples.load();
}

// A streaming read of 512 MiB on every core (the memory bandwidth): the
// wall and CPU ms of the best of 3, and the bytes read.
std::tuple<double, double, double> MeasureBandwidth(int threads, uint32_t& sink) {
  std::vector<uint32_t> big(size_t(1) << 27, 1u);
  const auto [read_ms, read_cpu_ms] = Measure(3, threads, [&] {
    std::vector<std::thread> pool;
    std::vector<uint32_t> sums(threads);
    const size_t chunk = big.size() / threads;
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] { sums[t] = SumWords(big.data() + t * chunk, chunk); });
    }
    for (auto& t : pool) t.join();
    for (uint32_t s : sums) sink += s;
  });
  return {read_ms, read_cpu_ms, double(big.size() * sizeof(uint32_t))};
}

}  // namespace

int main(int argc, char** argv) {
  const std::string source = argc > 1 ? argv[1] : "phantom:abdomen";
  const int size = argc > 2 ? std::atoi(argv[2]) : 512;
  if (!__builtin_cpu_supports("avx2") || !__builtin_cpu_supports("fma")) {
    std::fprintf(stderr, "sample_rate_bench: needs AVX2 and FMA\n");
    return 1;
  }
  auto volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  if (volume.voxels().floats().empty()) {
    std::fprintf(stderr,
                 "sample_rate_bench: %s is held as int16; give a float source "
                 "(the phantom)\n",
                 source.c_str());
    return 2;
  }
  const Rays rays = MakeRays(volume, size);
  const int dims[3] = {int(volume.dims()[0]), int(volume.dims()[1]), int(volume.dims()[2])};
  const int threads = int(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<float> image(size_t(size) * size);

  int64_t samples = 0;
  const auto [mip_ms, mip_cpu_ms] =
      Measure(5, threads, [&] { samples = CastMip(volume, rays, size, threads, image); });
  uint32_t sink = 0;
  const auto [read_ms, read_cpu_ms, bytes] = MeasureBandwidth(threads, sink);

  std::printf("machine limits, %s %lldx%lldx%lld (float32, %.0f MiB), %d threads\n",
              source.c_str(), (long long)dims[0], (long long)dims[1], (long long)dims[2],
              double(volume.voxels().floats().size() * 4) / double(1 << 20), threads);
  std::printf("| measure | wall | CPU time / %d |\n|---|---|---|\n", threads);
  std::printf("| MIP %dx%d, 1 mm, no skipping, AVX2 gathers: ms | %.1f | %.1f |\n", size, size,
              mip_ms, mip_cpu_ms);
  std::printf("| samples per frame (M) | %.2f | |\n", double(samples) * 1e-6);
  std::printf("| trilinear samples per second (M) | %.0f | %.0f |\n",
              double(samples) / mip_ms * 1e-3, double(samples) / mip_cpu_ms * 1e-3);
  std::printf("| streaming read, GB/s | %.1f | %.1f |\n", bytes / (read_ms * 1e6),
              bytes / (read_cpu_ms * 1e6));
  std::printf("(checksum %u)\n", sink);
  return 0;
}

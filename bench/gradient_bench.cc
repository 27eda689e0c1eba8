// Gradient magnitude of the 256^3 phantom: upload, GPU kernel, CPU reference
// (2 threads), readback, in ms and effective GB/s (bytes read + written by
// the kernel: 4 B in, 4 B out per voxel).
#include <cstdio>

#include "bench/bench_util.h"
#include "server/gpu/compute_batch.h"
#include "server/volume/gradient_magnitude.h"
#include "server/volume/gradient_magnitude_gpu.h"
#include "server/io/read_volume.h"

using namespace vpm;

int main(int argc, char** argv) {
  const std::string source = argc > 1 ? argv[1] : "phantom:abdomen";
  const int reps = 7;
  auto volume = bench::Check(ReadVolume(source, {}), "reading the volume");
  auto context = bench::Check(gpu::GpuContext::Create({}), "opening Vulkan");
  const auto& d = volume.dims();
  const double voxels = double(d[0]) * d[1] * d[2];
  const double bytes = voxels * 4.0;

  std::optional<GpuVolume> gpu_volume;
  const double upload_ms = bench::MinMs(reps, [&] {
    gpu_volume.emplace(bench::Check(GpuVolume::Upload(*context, volume), "upload"));
  });
  auto op = bench::Check(GradientMagnitudeGpu::Create(*context), "pipeline");
  auto out = bench::Check(gpu::GpuBuffer::Create(*context, size_t(bytes),
                                                 vk::BufferUsageFlagBits::eStorageBuffer),
                          "buffer");
  double kernel_ms = 1e300, submit_ms = 1e300;
  for (int r = 0; r < reps; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    auto batch = bench::Check(gpu::ComputeBatch::Begin(*context, 1), "batch");
    if (!op.Record(batch, *gpu_volume, out).ok()) return 1;
    auto timings = bench::Check(batch.SubmitAndWait(), "submit");
    submit_ms = std::min(submit_ms, MsSince(t0));
    kernel_ms = std::min(kernel_ms, timings.front().gpu_ms);
  }
  std::vector<float> result(static_cast<size_t>(voxels));
  const double readback_ms = bench::MinMs(reps, [&] {
    if (!out.DownloadSpan(std::span<float>(result)).ok()) std::exit(1);
  });
  std::vector<float> cpu;
  const double cpu_ms = bench::MinMs(reps, [&] { cpu = GradientMagnitude(volume, 2); });
  double max_err = 0, max_ref = 0;
  for (size_t n = 0; n < cpu.size(); ++n) {
    max_err = std::max(max_err, double(std::abs(cpu[n] - result[n])));
    max_ref = std::max(max_ref, double(cpu[n]));
  }

  std::printf("gradient magnitude, %s (%lldx%lldx%lld), device '%s', min of %d\n",
              source.c_str(), (long long)d[0], (long long)d[1], (long long)d[2],
              context->device_name().c_str(), reps);
  std::printf("%-34s %10s %10s\n", "stage", "ms", "GB/s");
  std::printf("%-34s %10.2f %10.2f\n", "upload (host -> 3D image)", upload_ms, bytes / upload_ms / 1e6);
  std::printf("%-34s %10.2f %10.2f\n", "GPU gradient (kernel, timestamps)", kernel_ms,
              2 * bytes / kernel_ms / 1e6);
  std::printf("%-34s %10.2f %10.2f\n", "GPU gradient (submit + wait)", submit_ms,
              2 * bytes / submit_ms / 1e6);
  std::printf("%-34s %10.2f %10.2f\n", "CPU reference (2 threads)", cpu_ms, 2 * bytes / cpu_ms / 1e6);
  std::printf("%-34s %10.2f %10.2f\n", "readback (buffer -> host)", readback_ms,
              bytes / readback_ms / 1e6);
  std::printf("GPU vs CPU max |error| / max = %.2e; CPU / GPU kernel time = %.2fx\n",
              max_err / max_ref, cpu_ms / kernel_ms);
  return 0;
}

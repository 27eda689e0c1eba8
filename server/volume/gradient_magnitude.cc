#include "server/volume/gradient_magnitude.h"

#include <algorithm>

#include "server/common/parallel_chunks.h"

namespace vpm {
namespace {

// One z slab; interior voxels skip the clamping of GradientMagnitudeAt.
// Voxels: Int16Voxels or FloatVoxels.
template <typename Voxels>
void GradientSlab(const Volume& v, const Voxels& data, int64_t k_begin, int64_t k_end,
                  float* out) {
  const auto [nx, ny, nz] = v.dims();
  const glm::dvec3& s = v.spacing_mm();
  for (int64_t k = k_begin; k < k_end; ++k) {
    for (int64_t j = 0; j < ny; ++j) {
      const bool interior_jk = j > 0 && j < ny - 1 && k > 0 && k < nz - 1;
      for (int64_t i = 0; i < nx; ++i) {
        const int64_t n = i + nx * (j + ny * k);
        if (!interior_jk || i == 0 || i == nx - 1) {
          out[n] = GradientMagnitudeAt(v, i, j, k);
          continue;
        }
        // Same operation order as GradientMagnitudeAt: (a - b) / (2 s).
        const float gx = (data[n + 1] - data[n - 1]) / float(2.0 * s.x);
        const float gy = (data[n + nx] - data[n - nx]) / float(2.0 * s.y);
        const float gz = (data[n + nx * ny] - data[n - nx * ny]) / float(2.0 * s.z);
        out[n] = std::sqrt(gx * gx + gy * gy + gz * gz);
      }
    }
  }
}

}  // namespace

std::vector<float> GradientMagnitude(const Volume& volume, int threads) {
  std::vector<float> out(static_cast<size_t>(volume.geometry().voxel_count()));
  const int64_t nz = volume.dims()[2];
  volume.voxels().Visit([&](const auto& voxels) {
    ParallelChunks(threads, nz, [&](int64_t k0, int64_t k1, int) {
      GradientSlab(volume, voxels, k0, k1, out.data());
    });
  });
  return out;
}

}  // namespace vpm

// Shared helpers of the render tests: the synthetic test volume, image
// comparisons (normalised errors, PSNR), and PNG dumps for eyeballing.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include "server/raycast/frame_encoder.h"
#include "server/volume/volume.h"

namespace vpm::testing {

// A 48^3 volume (anisotropic spacing 1.0 x 1.1 x 1.3 mm) in HU: air, a soft
// tissue slab (40 HU), a contrast sphere (200 HU) and a bone rod (700 HU)
// along z, edges ramped over about a voxel (partial volume), small
// deterministic noise.
inline Volume MakeSphereRodVolume(int n = 48) {
  VolumeGeometry g;
  g.dims = {n, n, n};
  g.spacing_mm = {1.0, 1.1, 1.3};
  std::vector<float> values(g.voxel_count());
  const glm::dvec3 extent = g.extent_mm();
  const glm::dvec3 centre = 0.5 * extent;
  uint64_t state = 0x2545F4914F6CDD1Dull;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 p = glm::dvec3(i, j, k) * g.spacing_mm;
        auto ramp = [](double d) { return std::clamp(0.5 - d, 0.0, 1.0); };  // d in mm
        double v = -1000.0;
        const double slab = std::max(std::abs(p.y - centre.y) - 0.3 * extent.y,
                                     std::abs(p.x - centre.x) - 0.4 * extent.x);
        v += (40.0 + 1000.0) * ramp(slab);
        const double sphere = glm::length(p - (centre + glm::dvec3(-6.0, 0.0, 4.0))) - 11.0;
        v += (200.0 - v) * ramp(sphere);
        const double rod = std::hypot(p.x - (centre.x + 11.0), p.y - (centre.y + 5.0)) - 4.0;
        v += (700.0 - v) * ramp(rod);
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        v += double((state >> 40) % 1000) * 0.004 - 2.0;  // +-2 HU
        values[i + n * (j + n * k)] = float(v);
      }
  return *Volume::Create(g, std::move(values));
}

// The 256^3 phantom's geometry (no voxels): 380 x 380 x 243 mm, so its DVR
// stills step 0.375 mm (the cap).
inline VolumeGeometry PhantomGeometry() {
  VolumeGeometry g;
  g.dims = {256, 256, 256};
  g.spacing_mm = {380.0 / 255.0, 380.0 / 255.0, 243.0 / 255.0};
  return g;
}

struct ImageError {
  double mean_abs = 0.0;  // over every channel of every pixel, in [0, 1]
  double max_abs = 0.0;   // in [0, 1]
  double psnr_db = 0.0;   // RGB
};

inline ImageError CompareRgba(std::span<const uint8_t> a, std::span<const uint8_t> b) {
  ImageError e;
  double sum = 0.0, sq = 0.0;
  int64_t count = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    if (i % 4 == 3) continue;
    const double d = std::abs(double(a[i]) - double(b[i])) / 255.0;
    sum += d;
    sq += d * d;
    e.max_abs = std::max(e.max_abs, d);
    ++count;
  }
  e.mean_abs = count ? sum / count : 0.0;
  const double mse = count ? sq / count : 0.0;
  e.psnr_db = mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : 99.0;
  return e;
}

// Writes `rgba` as PNG to $VPM_RENDER_DUMP_DIR/name.png when that variable is
// set (for looking at test frames).
inline void MaybeDump(const std::string& name, std::span<const uint8_t> rgba, int w, int h) {
  const char* dir = std::getenv("VPM_RENDER_DUMP_DIR");
  if (dir == nullptr) return;
  auto png = EncodePng(rgba, w, h);
  if (!png.ok()) return;
  std::ofstream(std::string(dir) + "/" + name + ".png", std::ios::binary)
      .write(reinterpret_cast<const char*>(png->data()), std::streamsize(png->size()));
}

}  // namespace vpm::testing

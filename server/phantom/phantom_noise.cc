#include "server/phantom/phantom_noise.h"

#include <cmath>
#include <numbers>

namespace vpm::phantom {
namespace {

constexpr float kTwoPi = 2.0f * std::numbers::pi_v<float>;
constexpr float kInv2Pow24 = 1.0f / 16777216.0f;

// One Box-Muller pair from one 64-bit hash: 24 bits for each uniform, so the
// deviates are bounded by sqrt(2 * 25 * ln 2) = 5.9 sigma (a CT has no
// heavier tails worth modelling).
struct GaussianPair {
  float cos_deviate;
  float sin_deviate;
};

GaussianPair PairFromHash(uint64_t h) {
  const float u1 = (static_cast<float>(h >> 40) + 1.0f) * kInv2Pow24;  // (0, 1]
  const float u2 = static_cast<float>(h & 0xFFFFFFu) * kInv2Pow24;     // [0, 1)
  const float r = std::sqrt(-2.0f * std::log(u1));
  const float angle = kTwoPi * u2;
  return {r * std::cos(angle), r * std::sin(angle)};
}

uint64_t StreamKey(uint64_t seed) { return SplitMix64(seed ^ 0x5851F42D4C957F2Dull); }

// Perlin's quintic fade: C2 blending weight for a lattice fraction t in [0, 1].
double Fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

}  // namespace

float GaussianDeviate(uint64_t seed, uint64_t index) {
  const GaussianPair pair = PairFromHash(SplitMix64(StreamKey(seed) ^ (index >> 1)));
  return (index & 1u) ? pair.sin_deviate : pair.cos_deviate;
}

void AddGaussianNoise(uint64_t seed, uint64_t first_index, float sigma_hu,
                      std::span<float> values) {
  if (sigma_hu == 0.0f || values.empty()) return;
  const uint64_t key = StreamKey(seed);
  size_t n = 0;
  uint64_t index = first_index;
  if (index & 1u) {  // the row starts on the second half of a pair
    values[n++] += sigma_hu * PairFromHash(SplitMix64(key ^ (index >> 1))).sin_deviate;
    ++index;
  }
  for (; n + 1 < values.size(); n += 2, index += 2) {
    const GaussianPair pair = PairFromHash(SplitMix64(key ^ (index >> 1)));
    values[n] += sigma_hu * pair.cos_deviate;
    values[n + 1] += sigma_hu * pair.sin_deviate;
  }
  if (n < values.size()) {
    values[n] += sigma_hu * PairFromHash(SplitMix64(key ^ (index >> 1))).cos_deviate;
  }
}

GradientNoise::GradientNoise(uint64_t seed, double cell_mm)
    : seed_(seed), inv_cell_(1.0 / cell_mm) {}

glm::dvec3 GradientNoise::Gradient(int64_t ix, int64_t iy, int64_t iz) const {
  uint64_t h = SplitMix64(seed_ ^ (static_cast<uint64_t>(ix) * 0x9E3779B97F4A7C15ull));
  h = SplitMix64(h ^ (static_cast<uint64_t>(iy) * 0xC2B2AE3D27D4EB4Full));
  h = SplitMix64(h ^ (static_cast<uint64_t>(iz) * 0x165667B19E3779F9ull));
  constexpr double kScale = 2.0 / 2097151.0;  // 21 bits per component -> [-1, 1]
  return {static_cast<double>(h & 0x1FFFFF) * kScale - 1.0,
          static_cast<double>((h >> 21) & 0x1FFFFF) * kScale - 1.0,
          static_cast<double>((h >> 42) & 0x1FFFFF) * kScale - 1.0};
}

double GradientNoise::At(double x_mm, double y_mm, double z_mm) const {
  float out = 0.0f;
  Row(x_mm, 1.0, y_mm, z_mm, std::span<float>(&out, 1));
  return out;
}

void GradientNoise::Row(double x0_mm, double dx_mm, double y_mm, double z_mm,
                        std::span<float> out) const {
  const double uy = y_mm * inv_cell_;
  const double uz = z_mm * inv_cell_;
  const int64_t iy = static_cast<int64_t>(std::floor(uy));
  const int64_t iz = static_cast<int64_t>(std::floor(uz));
  const double fy = uy - static_cast<double>(iy);
  const double fz = uz - static_cast<double>(iz);
  const double wy = Fade(fy);
  const double wz = Fade(fz);
  // Along a row only x varies, so the four nodes of lattice column ix add up
  // to offset(ix) + slope(ix) * (ux - ix): cache both per column.
  struct Column {
    double offset;
    double slope;
  };
  auto column = [&](int64_t ix) {
    Column c{0.0, 0.0};
    for (int b = 0; b < 2; ++b) {
      for (int d = 0; d < 2; ++d) {
        const double w = (b ? wy : 1.0 - wy) * (d ? wz : 1.0 - wz);
        const glm::dvec3 g = Gradient(ix, iy + b, iz + d);
        c.offset += w * (g.y * (fy - b) + g.z * (fz - d));
        c.slope += w * g.x;
      }
    }
    return c;
  };
  int64_t cached_ix = INT64_MIN;
  Column c0{};
  Column c1{};
  for (size_t n = 0; n < out.size(); ++n) {
    const double ux = (x0_mm + static_cast<double>(n) * dx_mm) * inv_cell_;
    const int64_t ix = static_cast<int64_t>(std::floor(ux));
    if (ix != cached_ix) {
      c0 = (ix == cached_ix + 1) ? c1 : column(ix);
      c1 = column(ix + 1);
      cached_ix = ix;
    }
    const double fx = ux - static_cast<double>(ix);
    const double v0 = c0.offset + c0.slope * fx;
    const double v1 = c1.offset + c1.slope * (fx - 1.0);
    out[n] = static_cast<float>(v0 + Fade(fx) * (v1 - v0));
  }
}

}  // namespace vpm::phantom

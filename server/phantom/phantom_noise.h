// Counter-based random numbers for the synthetic phantoms.
//
// Every value is a pure function of (seed, counter): no generator state is
// carried from one voxel to the next, so a volume comes out bit-identical
// whatever the thread count or the order in which slabs are filled.
#pragma once

#include <cstdint>
#include <span>

#include <glm/glm.hpp>

namespace vpm::phantom {

// splitmix64 (Steele, Lea, Flood 2014): a bijective 64-bit mix with full
// avalanche; hashing a counter with it is a counter-based generator.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// Standard normal deviate number `index` of stream `seed` (Box-Muller on one
// 64-bit hash per pair of indices: even indices take the cosine, odd the sine).
float GaussianDeviate(uint64_t seed, uint64_t index);

// values[n] += sigma_hu * GaussianDeviate(seed, first_index + n) for every n,
// one hash and one log per two voxels. sigma_hu: standard deviation in HU.
void AddGaussianNoise(uint64_t seed, uint64_t first_index, float sigma_hu, std::span<float> values);

// Smooth 3D gradient noise (Perlin's improved noise): a hashed gradient in
// [-1, 1]^3 at each node of a cubic lattice of `cell_mm`, blended with
// quintic fade weights; zero at the nodes, about +-1 in between, changing by
// about 1 per cell. Used for anatomy texture (bowel loops), so it is seeded by
// the anatomy, not by the noise seed.
class GradientNoise {
 public:
  GradientNoise(uint64_t seed, double cell_mm);

  // Noise at the world point (x, y, z), mm.
  double At(double x_mm, double y_mm, double z_mm) const;
  // out[n] = At(x0_mm + n * dx_mm, y_mm, z_mm), dx_mm > 0: one row, hashing
  // each lattice column once instead of once per point.
  void Row(double x0_mm, double dx_mm, double y_mm, double z_mm, std::span<float> out) const;

 private:
  glm::dvec3 Gradient(int64_t ix, int64_t iy, int64_t iz) const;

  uint64_t seed_;
  double inv_cell_;  // 1 / cell size, 1/mm
};

}  // namespace vpm::phantom

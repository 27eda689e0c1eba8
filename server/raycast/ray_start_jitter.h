// The jitter of a ray's first sample: raycast_body.glsl's ray_start_jitter
// (shaders/ray_jitter.glsl), bit for bit.
#pragma once

#include <cstdint>

namespace vpm {

// Chris Wellons' lowbias32 integer hash.
constexpr uint32_t JitterHash(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

// Inputs: pixel (px, py) of the ray-cast image, the frame's seed. Output: the
// first sample's offset along the ray as a fraction of the step, in [0, 1)
// (a multiple of 2^-24, exact in float).
constexpr float RayStartJitter(uint32_t px, uint32_t py, uint32_t seed) {
  const uint32_t h = JitterHash(px ^ JitterHash(py ^ JitterHash(seed)));
  return float(h >> 8) * (1.0f / 16777216.0f);
}

}  // namespace vpm

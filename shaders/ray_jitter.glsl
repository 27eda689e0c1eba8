// The jitter of a ray's first sample, as a fraction of the step in [0, 1):
// a hash of the pixel and the frame's seed (RaycastParams::image.w), so that
// neighbouring rays sample at unrelated depths (noise instead of the
// "wood-grain" rings of samples taken at equal depths) and one seed gives
// one picture. Integer arithmetic only: the CPU reference
// (server/raycast/ray_start_jitter.h) computes the same bits.
#ifndef VPM_RAY_JITTER_GLSL
#define VPM_RAY_JITTER_GLSL

// Chris Wellons' lowbias32 integer hash.
uint jitter_hash(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

float ray_start_jitter(uvec2 px, uint seed) {
  uint h = jitter_hash(px.x ^ jitter_hash(px.y ^ jitter_hash(seed)));
  return float(h >> 8) * (1.0 / 16777216.0);
}

#endif

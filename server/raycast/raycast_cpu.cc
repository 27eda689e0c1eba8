#include "server/raycast/raycast_cpu.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <thread>

#include "server/common/clock.h"
#include "server/raycast/clip_region.h"
#include "server/raycast/preintegrated_lut.h"
#include "server/raycast/ray_start_jitter.h"
#include "server/raycast/upscale_cpu.h"

namespace vpm {
namespace {

using glm::ivec3;
using glm::vec2;
using glm::vec3;
using glm::vec4;

constexpr float kOpaque = 0.99f;
constexpr float kShadeMinWeight = 1.0f / 256.0f;
constexpr float kNoValue = -3.0e38f;

// last_sample_t() of raycast_body.glsl: the last sample t_near + k step at
// or before t_far (t_near <= t_far), by the loops' arithmetic.
float LastSampleT(float t_near, float t_far, float step) {
  float k = std::floor((t_far - t_near) / step);
  if (t_near + (k + 1.0f) * step <= t_far) k += 1.0f;
  if (k > 0.0f && t_near + k * step > t_far) k -= 1.0f;
  return t_near + k * step;
}

// ends_opaque() of raycast_body.glsl: past kOpaque, the transmittance left
// takes the last step's colour, rgb / over (over: its opacity when rgb is
// premultiplied, else 1), and the ray ends.
bool EndsOpaque(vec3 rgb, float over, vec4& acc) {
  if (acc.a <= kOpaque) return false;
  acc += vec4((1.0f - acc.a) * (rgb / over), 0.0f);
  acc.a = 1.0f;
  return true;
}

// RayPeaks and peaks_add() of raycast_mip.glsl: a MIP ray's maximum so far
// (at sample k_best) and its largest sample at least two samples from it.
struct RayPeaks {
  float best = kNoValue;
  int k_best = -1;
  float second = kNoValue;
  int k_second = -1;

  void Add(float v, int k) {
    if (v > best) {
      if (std::abs(k - k_best) >= 2) {
        second = best;
        k_second = k_best;
      }
      best = v;
      k_best = k;
    } else if (v > second && std::abs(k - k_best) >= 2) {
      second = v;
      k_second = k;
    }
  }
};

// A trilinear cell's interpolant at fraction f (each in [0, 1]) and its
// partial derivatives per cell unit, for corner values c[x + 2y + 4z] of type
// T (float for the volume, vec3 for the backward map), in the order of
// operations of raycast_body.glsl so that both agree to the last bit.
template <typename T>
struct TrilinearWithPartials {
  T value, d_dx, d_dy, d_dz;
};

template <typename T>
TrilinearWithPartials<T> InterpolateCell(const T (&c)[8], vec3 f) {
  const T c00 = c[0] + (c[1] - c[0]) * f.x;
  const T c10 = c[2] + (c[3] - c[2]) * f.x;
  const T c01 = c[4] + (c[5] - c[4]) * f.x;
  const T c11 = c[6] + (c[7] - c[6]) * f.x;
  const T c0 = c00 + (c10 - c00) * f.y;
  const T c1 = c01 + (c11 - c01) * f.y;
  const T dx0 = (c[1] - c[0]) + ((c[3] - c[2]) - (c[1] - c[0])) * f.y;
  const T dx1 = (c[5] - c[4]) + ((c[7] - c[6]) - (c[5] - c[4])) * f.y;
  const T dy0 = c10 - c00;
  const T dy1 = c11 - c01;
  return {c0 + (c1 - c0) * f.z, dx0 + (dx1 - dx0) * f.z, dy0 + (dy1 - dy0) * f.z, c1 - c0};
}

uint32_t PackRgba(vec3 rgb) {
  const vec3 c = glm::clamp(rgb, 0.0f, 1.0f) * 255.0f + 0.5f;
  return uint32_t(c.r) | (uint32_t(c.g) << 8) | (uint32_t(c.b) << 16) | (255u << 24);
}

// Runs fn(row) for rows 0..rows-1 on `threads` threads, rows interleaved
// (neighbouring rows cost about the same).
template <typename Fn>
void ForRows(int rows, int threads, Fn fn) {
  threads = std::max(1, std::min(threads, rows));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) {
    pool.emplace_back([&, t] {
      for (int r = t; r < rows; r += threads) fn(r);
    });
  }
  for (int r = 0; r < rows; r += threads) fn(r);
  for (auto& th : pool) th.join();
}

// X(x) - x from the map: rest_from_texels() of raycast_body.glsl (the
// sampler's linear, clamp-to-edge filtering with exact weights).
vec3 MapDisplacement(const HostBackwardMap& map, vec3 x, vec3 extent, vec3 m) {
  const vec3 gc = glm::clamp(x / extent * (m - 1.0f), vec3(0.0f), m - 1.0f);
  const ivec3 mi(map.dims[0], map.dims[1], map.dims[2]);
  const ivec3 i0 = glm::min(ivec3(glm::floor(gc)), mi - 2);
  const vec3 f = gc - vec3(i0);
  auto at = [&](int dx, int dy, int dz) {
    return vec3(map.texels[(i0.x + dx) + size_t(mi.x) * ((i0.y + dy) + size_t(mi.y) * (i0.z + dz))]);
  };
  const vec3 c00 = at(0, 0, 0) + (at(1, 0, 0) - at(0, 0, 0)) * f.x;
  const vec3 c10 = at(0, 1, 0) + (at(1, 1, 0) - at(0, 1, 0)) * f.x;
  const vec3 c01 = at(0, 0, 1) + (at(1, 0, 1) - at(0, 0, 1)) * f.x;
  const vec3 c11 = at(0, 1, 1) + (at(1, 1, 1) - at(0, 1, 1)) * f.x;
  const vec3 c0 = c00 + (c10 - c00) * f.y;
  const vec3 c1 = c01 + (c11 - c01) * f.y;
  return c0 + (c1 - c0) * f.z;
}

// One frame's ray caster: raycast_body.glsl, function by function. Voxels:
// Int16Voxels or FloatVoxels (voxel_values.h), the decode of volume_access.glsl.
template <typename Voxels>
class Caster {
 public:
  Caster(const gpu::RaycastParams& p, const RaycastCpuInputs& in, Voxels voxels)
      : p_(p), in_(in), values_(voxels) {
    n_ = ivec3(p.dims);
    spacing_ = vec3(p.spacing_mm);
    extent_ = vec3(n_ - 1) * spacing_;
    flags_ = p.image.z;
    nb_ = ivec3(p.bricks);
    brick_size_ = spacing_ * vec3(ivec3(p.brick_voxels));
    inv_spacing_ = 1.0f / spacing_;
    inv_brick_ = 1.0f / brick_size_;
    mip_ = p.dims.w == 1;
    skipping_ = Flag(gpu::kRaycastSkipping);
    shading_ = Flag(gpu::kRaycastShading);
    early_ = Flag(gpu::kRaycastEarlyTermination);
    cell_ = Flag(kRaycastCellGradient);
    pre_ = !mip_ && cell_ && Flag(kRaycastPreintegrated);
    both_ends_ = Flag(gpu::kRaycastLightBothEnds);
  }

  // main() of raycast_body.glsl for pixel (px, py): its packed RGBA; adds
  // the samples read to `taken`.
  uint32_t Pixel(int px, int py, int64_t& taken) const;

 private:
  // One ray: its geometry (volume frame, mm; t in mm along dir) and what it
  // has gathered so far.
  struct Ray {
    vec3 eye, dir, inv_dir;
    float t_entry = 0.0f;  // where it enters the box and clip planes (before the jitter)
    float t_near = 0.0f;   // sample 0 (t_entry + jitter * step)
    float t_far = 0.0f;    // where it leaves them
    float step = 0.0f;     // mm between samples
    RayPeaks peaks;        // MIP
    vec4 acc{0.0f};        // DVR: premultiplied colour and opacity
    int k = 0;             // the next sample
    // Pre-integrated: the sample after the last one taken, and the value at
    // the front of the next step (as the shader).
    int k_next = 0;
    float front = 0.0f;
    bool has_front = false;
    vec2 light_front{0.0f};  // LightFactors at front, when has_light_front
    bool has_light_front = false;
    int64_t taken = 0;  // samples read
  };

  bool Flag(int f) const { return (flags_ & f) != 0; }

  float SourceAt(vec3 u) const {
    const ivec3 i0 = glm::min(ivec3(glm::floor(u)), n_ - 2);
    const vec3 f = u - vec3(i0);
    const int64_t sy = n_.x, sz = int64_t(n_.x) * n_.y;
    const int64_t n = i0.x + sy * i0.y + sz * i0.z;
    const float v000 = values_[n], v100 = values_[n + 1];
    const float v010 = values_[n + sy], v110 = values_[n + sy + 1];
    const float v001 = values_[n + sz], v101 = values_[n + sz + 1];
    const float v011 = values_[n + sz + sy], v111 = values_[n + sz + sy + 1];
    const float c00 = v000 + (v100 - v000) * f.x;
    const float c10 = v010 + (v110 - v010) * f.x;
    const float c01 = v001 + (v101 - v001) * f.x;
    const float c11 = v011 + (v111 - v011) * f.x;
    const float c0 = c00 + (c10 - c00) * f.y;
    const float c1 = c01 + (c11 - c01) * f.y;
    return c0 + (c1 - c0) * f.z;
  }

  float DeformedValue(vec3 x) const {
    const vec3 rest = Flag(gpu::kRaycastHasMap)
                          ? x + MapDisplacement(*in_.map, x, extent_, vec3(p_.map_dims))
                          : x;
    return SourceAt(glm::clamp(rest * inv_spacing_, vec3(0.0f), vec3(n_ - 1)));
  }

  // source_and_gradient() of raycast_body.glsl: I at u and its gradient
  // per voxel, that of the trilinear cell.
  float SourceAndGradient(vec3 u, vec3& grad_u) const {
    const ivec3 i0 = glm::min(ivec3(glm::floor(u)), n_ - 2);
    const vec3 f = u - vec3(i0);
    const int64_t sy = n_.x, sz = int64_t(n_.x) * n_.y;
    const int64_t n = i0.x + sy * i0.y + sz * i0.z;
    const float c[8] = {values_[n],      values_[n + 1],      values_[n + sy],
                        values_[n + sy + 1], values_[n + sz],  values_[n + sz + 1],
                        values_[n + sz + sy], values_[n + sz + sy + 1]};
    const TrilinearWithPartials<float> t = InterpolateCell(c, f);
    grad_u = vec3(t.d_dx, t.d_dy, t.d_dz);
    return t.value;
  }

  // deformed_value_and_gradient() of raycast_body.glsl: J(x) and grad J
  // (value/mm) by the chain rule through the trilinear map cell.
  float DeformedValueAndGradient(vec3 x, vec3& grad) const {
    vec3 rest = x;
    glm::mat3 jacobian(1.0f);  // d rest / d x, columns per x axis
    if (Flag(gpu::kRaycastHasMap)) {
      const HostBackwardMap& map = *in_.map;
      const vec3 m(p_.map_dims);
      const vec3 to_grid = (m - 1.0f) / extent_;
      const vec3 gc = glm::clamp(x * to_grid, vec3(0.0f), m - 1.0f);
      const ivec3 mi(map.dims[0], map.dims[1], map.dims[2]);
      const ivec3 i0 = glm::min(ivec3(glm::floor(gc)), mi - 2);
      const vec3 f = gc - vec3(i0);
      auto at = [&](int dx, int dy, int dz) {
        return vec3(
            map.texels[(i0.x + dx) + size_t(mi.x) * ((i0.y + dy) + size_t(mi.y) * (i0.z + dz))]);
      };
      const vec3 c[8] = {at(0, 0, 0), at(1, 0, 0), at(0, 1, 0), at(1, 1, 0),
                         at(0, 0, 1), at(1, 0, 1), at(0, 1, 1), at(1, 1, 1)};
      const TrilinearWithPartials<vec3> t = InterpolateCell(c, f);
      rest = x + t.value;
      jacobian[0] += t.d_dx * to_grid.x;
      jacobian[1] += t.d_dy * to_grid.y;
      jacobian[2] += t.d_dz * to_grid.z;
    }
    vec3 grad_u;
    const float v =
        SourceAndGradient(glm::clamp(rest * inv_spacing_, vec3(0.0f), vec3(n_ - 1)), grad_u);
    const vec3 grad_rest = grad_u * inv_spacing_;
    grad = vec3(glm::dot(jacobian[0], grad_rest), glm::dot(jacobian[1], grad_rest),
                glm::dot(jacobian[2], grad_rest));
    return v;
  }

  vec4 LutAt(float v) const {
    const auto& e = in_.lut->entries;
    const float n = p_.lut.z;
    const float f = std::clamp((v - p_.lut.x) * p_.lut.y, 0.0f, n - 1.0f);
    const int i = std::min(int(f), int(n) - 2);
    const float t = f - float(i);
    return e[i] + (e[i + 1] - e[i]) * t;
  }

  // The gradient of J at x by central differences, one spacing wide.
  vec3 TapGradient(vec3 x) const {
    const vec3 h = spacing_;
    const vec3 g(DeformedValue(x + vec3(h.x, 0, 0)) - DeformedValue(x - vec3(h.x, 0, 0)),
                 DeformedValue(x + vec3(0, h.y, 0)) - DeformedValue(x - vec3(0, h.y, 0)),
                 DeformedValue(x + vec3(0, 0, h.z)) - DeformedValue(x - vec3(0, 0, h.z)));
    return g / (2.0f * h);
  }

  // light_factors() of raycast_body.glsl: (ambient + diffuse, specular) of
  // a headlight on the gradient g (value/mm), lit_by() applies them.
  vec2 LightFactors(vec3 g, vec3 dir) const {
    const float len = glm::length(g);
    const float ndl = len > 0.0f ? std::abs(glm::dot(g, dir)) / len : 1.0f;
    const float s = len / (len + p_.gradient.x);
    const float n = p_.shading.w;
    const float spec = ndl / (n - n * ndl + ndl);  // Schlick's ndl^n
    const float diffuse = 1.0f + (ndl - 1.0f) * s;
    return vec2(p_.shading.x + p_.shading.y * diffuse, p_.shading.z * spec * s);
  }

  // alpha: 1 for a colour, the opacity for a premultiplied one.
  static vec3 LitBy(vec3 rgb, vec2 light, float alpha) {
    return glm::min(rgb * light.x + vec3(alpha * light.y), vec3(alpha));
  }

  // shade() of raycast_body.glsl.
  vec3 Shade(vec3 rgb, vec3 g, vec3 dir, float alpha = 1.0f) const {
    return LitBy(rgb, LightFactors(g, dir), alpha);
  }

  // preintegrated_at() of raycast_body.glsl.
  vec4 PreintegratedAt(float front, float back) const {
    const std::vector<vec4>& table = *in_.preintegrated;
    const float n = p_.lut.w;
    const float scale = p_.lut.y * (n - 1.0f) / (p_.lut.z - 1.0f);
    const float ff = std::clamp((front - p_.lut.x) * scale, 0.0f, n - 1.0f);
    const float fb = std::clamp((back - p_.lut.x) * scale, 0.0f, n - 1.0f);
    const int ni = int(n);
    const int i = std::min(int(ff), ni - 2), j = std::min(int(fb), ni - 2);
    const float s = ff - float(i), t = fb - float(j);
    const size_t base = size_t(i) + size_t(ni) * j;
    const vec4 ab = table[base] + (table[base + 1] - table[base]) * s;
    const vec4 cd = table[base + ni] + (table[base + ni + 1] - table[base + ni]) * s;
    return ab + (cd - ab) * t;
  }

  ivec3 BrickOf(vec3 x) const {
    return glm::clamp(ivec3(glm::floor(x * inv_brick_)), ivec3(0), nb_ - 1);
  }

  float BrickExit(vec3 x, vec3 eye, vec3 inv_dir) const {
    const ivec3 b = BrickOf(x);
    const vec3 lo = vec3(b) * brick_size_;
    const vec3 hi = glm::min(vec3(b + 1) * brick_size_, extent_);
    vec3 t;
    for (int a = 0; a < 3; ++a) t[a] = ((inv_dir[a] > 0.0f ? hi[a] : lo[a]) - eye[a]) * inv_dir[a];
    return std::min(t.x, std::min(t.y, t.z));
  }

  // The brick walk of raycast_body.glsl (walk_start, walk_exit, walk_step,
  // walk_to_occupied): the same arithmetic, so the same bricks and samples.
  struct BrickWalk {
    ivec3 b;
    vec3 t_next;
    float t_enter;
  };

  BrickWalk WalkStart(vec3 eye, vec3 dir, vec3 inv_dir, float t_near) const {
    BrickWalk w;
    w.b = BrickOf(eye + t_near * dir);
    const vec3 face = vec3(w.b + ivec3(glm::greaterThan(inv_dir, vec3(0.0f)))) * brick_size_;
    w.t_next = (face - eye) * inv_dir;
    w.t_enter = t_near;
    return w;
  }

  static float WalkExit(const BrickWalk& w) {
    return std::min(w.t_next.x, std::min(w.t_next.y, w.t_next.z));
  }

  static void WalkStep(BrickWalk& w, ivec3 step_b, vec3 t_delta) {
    const bool ax = w.t_next.x <= w.t_next.y && w.t_next.x <= w.t_next.z;
    const bool ay = !ax && w.t_next.y <= w.t_next.z;
    const glm::bvec3 m(ax, ay, !ax && !ay);
    w.t_enter = WalkExit(w);
    w.b += ivec3(m) * step_b;
    w.t_next += vec3(m) * t_delta;
  }

  // `sampled`: a brick already sampled (MIP, WalkToBrightest), walked over.
  bool WalkToOccupied(BrickWalk& w, int& k, float threshold, ivec3 step_b, vec3 t_delta,
                      float t_near, float t_far, float step, ivec3 sampled) const {
    for (;;) {
      if (w.t_enter > t_far) return false;
      const int first = std::max(k, int(std::ceil((w.t_enter - t_near) / step)));
      const float t_first = t_near + float(first) * step;
      if (t_first <= std::min(WalkExit(w), t_far) && w.b != sampled &&
          Occupancy(w.b) > threshold) {
        k = first;
        return true;
      }
      WalkStep(w, step_b, t_delta);
    }
  }

  // walk_to_brightest() of raycast_mip.glsl: the brick holding a sample
  // whose occupancy is the largest above black (the first at or above white
  // ends the walk); false when none is above black.
  bool WalkToBrightest(BrickWalk w, ivec3 step_b, vec3 t_delta, float t_near, float t_far,
                       float step, BrickWalk& bright, int& k_bright) const {
    const float black = p_.window.x, white = p_.window.z;
    float best = black;
    for (; w.t_enter <= t_far && best < white; WalkStep(w, step_b, t_delta)) {
      const int first = std::max(0, int(std::ceil((w.t_enter - t_near) / step)));
      const float t_first = t_near + float(first) * step;
      const float occ = Occupancy(w.b);
      if (t_first <= std::min(WalkExit(w), t_far) && occ > best) {
        best = occ;
        bright = w;
        k_bright = first;
      }
    }
    return best > black;
  }

  // refine_peaks() of raycast_mip.glsl, for one peak: around the ray's
  // sample k_max of value v_max, the points half, a quarter and an eighth of
  // a step either side of the best so far (within [t_entry, t_far]); the
  // largest value read. Six reads.
  float RefinePeak(Ray& r, float v_max, int k_max) const {
    r.taken += 6;
    float best_t = r.t_near + float(k_max) * r.step;
    float best = v_max;
    float h = 0.5f * r.step;
    for (int i = 0; i < 3; ++i) {
      const float t_before = std::clamp(best_t - h, r.t_entry, r.t_far);
      const float t_after = std::clamp(best_t + h, r.t_entry, r.t_far);
      const float before = DeformedValue(r.eye + t_before * r.dir);
      const float after = DeformedValue(r.eye + t_after * r.dir);
      if (before > best) {
        best = before;
        best_t = t_before;
      }
      if (after > best) {
        best = after;
        best_t = t_after;
      }
      h *= 0.5f;
    }
    return best;
  }

  float Occupancy(ivec3 b) const {
    const ivec3 c = glm::clamp(b, ivec3(0), nb_ - 1);
    return in_.occupancy[c.x + nb_.x * (c.y + nb_.y * c.z)];
  }

  // The ray through pixel (px, py); none when it misses the box or the
  // clip planes leave nothing of it.
  std::optional<Ray> StartRay(int px, int py) const;
  // composite_step() of raycast_body.glsl: the pre-integrated step c ending
  // at a sample of gradient g; true when the ray is done.
  bool CompositeStep(Ray& r, vec4 c, vec3 g, float min_weight) const;
  // composite_partial_step(): the partial step from t_front to t_back, lit
  // by t_back's light alone; two reads; front becomes t_back's value.
  bool CompositePartialStep(Ray& r, float t_front, float t_back) const;
  // Sample k_sample at x: true when the ray is done (early termination).
  bool Sample(Ray& r, vec3 x, int k_sample) const;
  // MIP and cell gradients: segments of the brick walk (raycast_body.glsl),
  // the samples of one occupied brick, then the walk to the next.
  void WalkBricks(Ray& r) const;
  // The walk's segments from r.k on: true when the ray is done.
  bool SampleSegments(Ray& r, BrickWalk& walk, ivec3 step_b, vec3 t_delta, ivec3 sampled) const;
  // Tap gradients: sample by sample, skipping empty bricks.
  void MarchTaps(Ray& r) const;

  const gpu::RaycastParams& p_;
  const RaycastCpuInputs& in_;
  Voxels values_;
  ivec3 n_, nb_;
  vec3 spacing_, extent_, brick_size_, inv_spacing_, inv_brick_;
  int flags_ = 0;
  bool mip_ = false, skipping_ = false, shading_ = false, early_ = false, cell_ = false;
  bool pre_ = false, both_ends_ = false;
};

template <typename Voxels>
std::optional<typename Caster<Voxels>::Ray> Caster<Voxels>::StartRay(int px, int py) const {
  Ray r;
  const vec2 ndc(2.0f * (float(px) + 0.5f) / float(p_.image.x) - 1.0f,
                 1.0f - 2.0f * (float(py) + 0.5f) / float(p_.image.y));
  r.eye = vec3(p_.eye_mm);
  r.dir = glm::normalize(vec3(p_.forward) + ndc.x * vec3(p_.right) + ndc.y * vec3(p_.up));
  for (int a = 0; a < 3; ++a) {
    const float d = r.dir[a];
    const float safe = std::abs(d) < 1e-20f ? (d < 0.0f ? -1e-20f : 1e-20f) : d;
    r.inv_dir[a] = 1.0f / safe;
  }
  const vec3 ta = (vec3(0.0f) - r.eye) * r.inv_dir;
  const vec3 tb = (extent_ - r.eye) * r.inv_dir;
  const vec3 tmin = glm::min(ta, tb), tmax = glm::max(ta, tb);
  r.t_near = std::max(std::max(std::max(tmin.x, tmin.y), tmin.z), 0.0f);
  r.t_far = std::min(std::min(tmax.x, tmax.y), tmax.z);
  ClipRayInterval(std::span<const vec4>(p_.clip_planes, size_t(p_.clip.x)), r.eye, r.dir,
                  r.t_near, r.t_far);
  if (r.t_near > r.t_far) return std::nullopt;
  r.step = p_.eye_mm.w;
  r.t_entry = r.t_near;
  if (Flag(gpu::kRaycastJitter)) {
    r.t_near += RayStartJitter(uint32_t(px), uint32_t(py), uint32_t(p_.image.w)) * r.step;
  }
  return r;
}

template <typename Voxels>
bool Caster<Voxels>::CompositeStep(Ray& r, vec4 c, vec3 g, float min_weight) const {
  const float transmitted = 1.0f - r.acc.a;
  vec3 rgb(c);
  if (shading_) {
    // The step's light: the mean of its two ends' (trapezoid rule).
    const vec2 light = LightFactors(g, r.dir);
    const vec2 seg = r.has_light_front ? 0.5f * (light + r.light_front) : light;
    r.light_front = light;
    r.has_light_front = both_ends_;
    rgb = transmitted * c.a > min_weight
              ? LitBy(rgb, seg, c.a)
              : glm::min(rgb * (p_.shading.x + p_.shading.y), vec3(c.a));
  }
  if (c.a <= 0.0f) return false;
  r.acc += vec4(transmitted * rgb, transmitted * c.a);
  return early_ && EndsOpaque(rgb, c.a, r.acc);
}

template <typename Voxels>
bool Caster<Voxels>::CompositePartialStep(Ray& r, float t_front, float t_back) const {
  r.taken += 2;
  vec3 g_back(0.0f);
  const float v_front = DeformedValue(r.eye + t_front * r.dir);
  r.front = DeformedValueAndGradient(r.eye + t_back * r.dir, g_back);
  r.has_front = true;
  const float fraction = std::clamp((t_back - t_front) / r.step, 0.0f, 1.0f);
  r.has_light_front = false;
  return CompositeStep(r, PartialPreintegratedStep(PreintegratedAt(v_front, r.front), fraction),
                       g_back, kShadeMinWeight * r.step * fraction);
}

template <typename Voxels>
bool Caster<Voxels>::Sample(Ray& r, vec3 x, int k_sample) const {
  ++r.taken;
  vec3 cell_gradient(0.0f);
  const float v = cell_ ? DeformedValueAndGradient(x, cell_gradient) : DeformedValue(x);
  if (mip_) {
    r.peaks.Add(v, k_sample);
    return early_ && r.peaks.best >= p_.window.z;  // white: no later sample shows
  }
  if (pre_) {
    // composite_segment() of raycast_body.glsl.
    const vec4 c = PreintegratedAt(r.has_front ? r.front : v, v);
    r.front = v;
    r.has_front = true;
    return CompositeStep(r, c, cell_gradient, kShadeMinWeight * r.step);
  }
  const vec4 c = LutAt(v);
  if (c.a <= 0.0f) return false;
  vec3 rgb = vec3(c);
  if (shading_) {
    // Per mm of ray with the cell gradient (raycast_body.glsl).
    rgb = (1.0f - r.acc.a) * c.a > (cell_ ? kShadeMinWeight * r.step : kShadeMinWeight)
              ? Shade(rgb, cell_ ? cell_gradient : TapGradient(x), r.dir)
              : glm::min(rgb * (p_.shading.x + p_.shading.y), vec3(1.0f));
  }
  const float w = (1.0f - r.acc.a) * c.a;
  r.acc += vec4(w * rgb, w);
  return early_ && EndsOpaque(rgb, 1.0f, r.acc);
}

template <typename Voxels>
void Caster<Voxels>::WalkBricks(Ray& r) const {
  BrickWalk walk = WalkStart(r.eye, r.dir, r.inv_dir, r.t_near);
  const ivec3 step_b(r.inv_dir.x < 0.0f ? -1 : 1, r.inv_dir.y < 0.0f ? -1 : 1,
                     r.inv_dir.z < 0.0f ? -1 : 1);
  const vec3 t_delta = brick_size_ * glm::abs(r.inv_dir);
  bool done = false;
  // Partial end steps (raycast_body.glsl): entry to sample 0, then the walk
  // from sample 1.
  const bool partial_ends = pre_ && Flag(gpu::kRaycastPartialEndSteps);
  if (partial_ends) {
    done = CompositePartialStep(r, r.t_entry, std::min(r.t_near, r.t_far));
    r.k = r.k_next = 1;
  }
  ivec3 sampled(-(1 << 20));  // none
  BrickWalk bright;
  int k_bright = 0;
  if (mip_ && skipping_ && Flag(gpu::kRaycastBrightestFirst) &&
      WalkToBrightest(walk, step_b, t_delta, r.t_near, r.t_far, r.step, bright, k_bright)) {
    const float t_end = std::min(WalkExit(bright), r.t_far);
    for (float t = r.t_near + float(k_bright) * r.step; !done && t <= t_end;
         t = r.t_near + float(k_bright) * r.step) {
      done = Sample(r, r.eye + t * r.dir, k_bright);
      ++k_bright;
    }
    sampled = bright.b;
  }
  if (!done) done = SampleSegments(r, walk, step_b, t_delta, sampled);
  if (partial_ends && !done && r.t_near <= r.t_far) {
    CompositePartialStep(r, LastSampleT(r.t_near, r.t_far, r.step), r.t_far);
  }
  if (mip_ && Flag(gpu::kRaycastPeakRefine) && !done && r.peaks.k_best >= 0) {
    float refined = RefinePeak(r, r.peaks.best, r.peaks.k_best);
    if (r.peaks.k_second >= 0) {
      refined = std::max(refined, RefinePeak(r, r.peaks.second, r.peaks.k_second));
    }
    r.peaks.best = refined;
  }
}

template <typename Voxels>
bool Caster<Voxels>::SampleSegments(Ray& r, BrickWalk& walk, ivec3 step_b, vec3 t_delta,
                                    ivec3 sampled) const {
  for (;;) {
    float t_end = r.t_far;
    if (skipping_) {
      const float threshold = mip_ ? std::max(r.peaks.best, p_.window.x) : 0.0f;
      if (!WalkToOccupied(walk, r.k, threshold, step_b, t_delta, r.t_near, r.t_far, r.step,
                          sampled)) {
        return false;
      }
      t_end = std::min(WalkExit(walk), r.t_far);
    }
    if (pre_) {
      if (r.k != r.k_next) {
        r.has_front = r.k > 0;
        r.has_light_front = false;
        r.front = DeformedValue(r.eye + (r.t_near + float(r.k - 1) * r.step) * r.dir);
      }
      t_end = std::min(t_end + r.step, r.t_far);
    }
    for (float t = r.t_near + float(r.k) * r.step; t <= t_end;
         t = r.t_near + float(r.k) * r.step) {
      const bool done = Sample(r, r.eye + t * r.dir, r.k);
      ++r.k;
      if (done) return true;
    }
    r.k_next = r.k;
    if (!skipping_) return false;
    WalkStep(walk, step_b, t_delta);
  }
}

template <typename Voxels>
void Caster<Voxels>::MarchTaps(Ray& r) const {
  for (;;) {
    const float t = r.t_near + float(r.k) * r.step;
    if (t > r.t_far) return;
    const vec3 x = r.eye + t * r.dir;
    if (skipping_) {
      const float occ = Occupancy(BrickOf(x));
      const bool empty = mip_ ? occ <= std::max(r.peaks.best, p_.window.x) : occ <= 0.0f;
      if (empty) {
        const float t_exit = BrickExit(x, r.eye, r.inv_dir);
        r.k = std::max(r.k + 1, int(std::floor((t_exit - r.t_near) / r.step)) + 1);
        continue;
      }
    }
    if (Sample(r, x, r.k)) return;
    ++r.k;
  }
}

template <typename Voxels>
uint32_t Caster<Voxels>::Pixel(int px, int py, int64_t& taken) const {
  const vec3 background(p_.background);
  std::optional<Ray> ray = StartRay(px, py);
  if (!ray) return PackRgba(background);
  Ray& r = *ray;
  if (mip_ || cell_) {
    WalkBricks(r);
  } else {
    MarchTaps(r);
  }
  taken += r.taken;
  const vec3 rgb = mip_ ? vec3(std::clamp((r.peaks.best - p_.window.x) * p_.window.y, 0.0f, 1.0f))
                        : vec3(r.acc) + (1.0f - r.acc.a) * background;
  return PackRgba(rgb);
}

// The frame's brick occupancy (empty with skipping off), from the caller's
// brick min-max grid or one computed here; sets frame.total_bricks and
// frame.occupied_bricks.
Result<std::vector<float>> ReferenceOccupancy(const RenderRequest& request, const Volume& volume,
                                              const HostBackwardMap* map,
                                              const std::vector<glm::vec2>* brick_minmax,
                                              const RaycastSetup& setup, const RenderLut& lut,
                                              Frame& frame) {
  const VolumeGeometry& g = volume.geometry();
  const ivec3 brick_voxels(setup.params.brick_voxels);
  const auto nb = BrickGridDims(g.dims, brick_voxels);
  frame.total_bricks = int64_t(nb[0]) * nb[1] * nb[2];
  if (brick_minmax != nullptr && int64_t(brick_minmax->size()) != frame.total_bricks) {
    return absl::InvalidArgumentError(
        StrCat("brick_minmax holds ", brick_minmax->size(), " bricks; bricks of ", brick_voxels.x,
               " x ", brick_voxels.y, " x ", brick_voxels.z, " voxels make ", frame.total_bricks));
  }
  std::vector<float> occupancy;
  if (!request.settings.empty_space_skipping) return occupancy;
  std::vector<glm::vec2> own;
  if (brick_minmax == nullptr) own = BrickMinMaxCpu(volume, brick_voxels);
  occupancy = BrickOccupancyCpu(brick_minmax ? *brick_minmax : own, g, brick_voxels, request.mode,
                                lut, map);
  const float black = setup.params.window.x;
  const bool mip = request.mode == RenderMode::kMip;
  frame.occupied_bricks = std::count_if(occupancy.begin(), occupancy.end(),
                                        [&](float o) { return mip ? o > black : o > 0.0f; });
  return occupancy;
}

}  // namespace

std::vector<uint32_t> RaycastCpu(const gpu::RaycastParams& params, const RaycastCpuInputs& in,
                                 int threads, int64_t* samples) {
  const int w = params.image.x, h = params.image.y;
  std::vector<uint32_t> pixels(size_t(w) * h);
  std::atomic<int64_t> total{0};
  in.volume->voxels().Visit([&](auto voxels) {
    const Caster caster(params, in, voxels);
    ForRows(h, threads, [&](int y) {
      int64_t taken = 0;
      for (int x = 0; x < w; ++x) pixels[size_t(y) * w + x] = caster.Pixel(x, y, taken);
      total += taken;
    });
  });
  if (samples != nullptr) *samples = total;
  return pixels;
}

Result<Frame> RenderReference(const RenderRequest& request, const Volume& volume,
                              const HostBackwardMap* map, int threads,
                              const std::vector<glm::vec2>* brick_minmax) {
  const auto t_start = std::chrono::steady_clock::now();
  const VolumeGeometry& g = volume.geometry();
  std::array<int, 3> map_dims{0, 0, 0};
  if (map != nullptr) {
    map_dims = map->dims;
    if (map->texels.size() != size_t(map_dims[0]) * map_dims[1] * map_dims[2]) {
      return absl::InvalidArgumentError("host backward map: texel count does not match dims");
    }
  }
  ASSIGN_OR_RETURN(RaycastSetup setup, PrepareRaycast(request, g, map_dims));
  const RenderLut lut = BakeRenderLut(request.preset, setup.step_mm);
  setup.params.lut = LutParams(lut);
  Frame frame;
  frame.width = request.width;
  frame.height = request.height;
  frame.render_width = setup.render_width;
  frame.render_height = setup.render_height;
  frame.step_mm = setup.step_mm;
  auto t0 = std::chrono::steady_clock::now();
  ASSIGN_OR_RETURN(const std::vector<float> occupancy,
                   ReferenceOccupancy(request, volume, map, brick_minmax, setup, lut, frame));
  frame.timings.occupancy_ms = MsSince(t0);
  t0 = std::chrono::steady_clock::now();
  std::vector<glm::vec4> preintegrated;
  if (setup.params.image.z & kRaycastPreintegrated) {
    preintegrated = BakePreintegratedLut(request.preset, setup.step_mm);
  }
  const RaycastCpuInputs inputs{&volume, map, &lut, occupancy, &preintegrated};
  int64_t samples = 0;
  std::vector<uint32_t> pixels = RaycastCpu(setup.params, inputs, threads, &samples);
  if (request.settings.count_samples) frame.samples = samples;
  frame.timings.raycast_ms = MsSince(t0);
  if (setup.render_width != request.width || setup.render_height != request.height) {
    t0 = std::chrono::steady_clock::now();
    pixels = UpscaleCpu(pixels, setup.render_width, setup.render_height, request.width,
                        request.height, UpscaleFilterOf(request));
    frame.timings.upscale_ms = MsSince(t0);
  }
  frame.rgba.resize(pixels.size() * 4);
  std::memcpy(frame.rgba.data(), pixels.data(), frame.rgba.size());
  t0 = std::chrono::steady_clock::now();
  DrawOverlay(request.overlay, request.camera, frame.width, frame.height, frame.rgba);
  frame.timings.overlay_ms = MsSince(t0);
  frame.timings.wall_ms = MsSince(t_start);
  return frame;
}

}  // namespace vpm

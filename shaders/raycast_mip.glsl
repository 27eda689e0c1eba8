// MIP along one ray, included by raycast_body.glsl (after the brick walk,
// raycast_brick_walk.glsl) where VPM_RAYCAST_MIP is defined. The CPU
// reference, Caster in server/raycast/raycast_cpu.cc, mirrors it.
#ifndef VPM_RAYCAST_MIP_GLSL
#define VPM_RAYCAST_MIP_GLSL

// MIP, the brightest brick first (docs/RENDERING.md, "Empty-space
// skipping"): walks the whole ray once, taking no sample, to the brick that
// holds a sample (index >= 0) and whose occupancy, the most it can show, is
// the largest above black; the first at or above white ends the walk. Sets
// bright to the walk there and k_bright to its first sample; false when no
// brick is above black. Caster::WalkToBrightest in raycast_cpu.cc mirrors it.
bool walk_to_brightest(BrickWalk w, float black, float white, float t_near, float t_far,
                       float step, out BrickWalk bright, out int k_bright) {
  float best = black;
  bright = w;
  k_bright = 0;
  while (w.t_enter <= t_far && best < white) {
    float occ = brick_occupancy(w.b);
    int k = 0;
    if (enter_brick(w, occ, k, best, t_near, t_far, step)) {
      best = occ;
      bright = w;
      k_bright = k;
    }
    walk_step(w);
  }
  return best > black;
}

// What a ray's samples have shown so far: the maximum (`best`, at sample
// k_best) and the largest sample at least two samples away from k_best
// (`second`: another structure, whose peak may be the higher one between
// the samples; k_second -1: none yet). RayPeaks in raycast_cpu.cc on the
// CPU.
struct RayPeaks {
  float best;
  int k_best;
  float second;
  int k_second;
};

void peaks_add(inout RayPeaks p, float v, int k) {
  if (v > p.best) {
    if (abs(k - p.k_best) >= 2) {
      p.second = p.best;
      p.k_second = p.k_best;
    }
    p.best = v;
    p.k_best = k;
  } else if (v > p.second && abs(k - p.k_best) >= 2) {
    p.second = v;
    p.k_second = k;
  }
}

// The MIP samples from k to t_end (k is in the segment), two per iteration
// (docs/LAVAPIPE.md, "Two samples per iteration"): both reads first, then
// the peaks sample by sample. Leaves k past the last sample taken; true
// when the maximum reaches white (early termination).
bool mip_segment(inout int k, float t_end, float t_near, float step, vec3 eye, vec3 dir,
                 bool early, float white, inout RayPeaks peaks, inout uint taken) {
  vec3 x;
  segment_sample(k, t_near, step, t_end, eye, dir, x);
  for (;;) {
    vec3 x2;
    bool second = segment_sample(k + 1, t_near, step, t_end, eye, dir, x2);
    float v1 = deformed_value(x);
    float v2 = deformed_value(second ? x2 : x);
    peaks_add(peaks, v1, k);
    ++taken;
    ++k;
    if (early && peaks.best >= white) return true;
    if (second) {
      peaks_add(peaks, v2, k);
      ++taken;
      ++k;
      if (early && peaks.best >= white) return true;
    }
    if (!segment_sample(k, t_near, step, t_end, eye, dir, x)) return false;
  }
}

// The peaks refined (docs/RENDERING.md, "Sampling"): a ray's brightest
// sample (value v at sample k) is rarely on the peak of a thin bright
// structure, which lies within a step of it. A bracketing search there: the
// values half a step either side, the best of the three kept, then a
// quarter step either side of it, then an eighth; where the ray is
// one-peaked within the step, the last best is within a sixteenth of a step
// of the peak. Points are clamped to [t_lo, t_hi], the ray's own interval
// un-jittered, so every value read is one the ray passes through and the
// maximum only rises toward the true one. Both peaks' searches run in one
// loop, four reads in flight per iteration (as "Two samples per iteration"
// does for the samples); a ray with no second peak searches its first
// twice, which changes nothing. Six reads per peak; the maximum of both
// searches, each as Caster::RefinePeak.
float refine_peaks(RayPeaks peaks, float t_near, float step, float t_lo, float t_hi, vec3 eye,
                   vec3 dir, inout uint taken) {
  bool has_second = peaks.k_second >= 0;
  vec2 best_t = t_near + vec2(peaks.k_best, has_second ? peaks.k_second : peaks.k_best) * step;
  vec2 best = vec2(peaks.best, has_second ? peaks.second : peaks.best);
  float h = 0.5 * step;
  for (int i = 0; i < 3; ++i) {
    vec2 t_before = clamp(best_t - h, t_lo, t_hi);
    vec2 t_after = clamp(best_t + h, t_lo, t_hi);
    vec2 before = vec2(deformed_value(eye + t_before.x * dir),
                       deformed_value(eye + t_before.y * dir));
    vec2 after = vec2(deformed_value(eye + t_after.x * dir),
                      deformed_value(eye + t_after.y * dir));
    bvec2 b = greaterThan(before, best);
    best = mix(best, before, b);
    best_t = mix(best_t, t_before, b);
    bvec2 a = greaterThan(after, best);
    best = mix(best, after, a);
    best_t = mix(best_t, t_after, a);
    h *= 0.5;
  }
  taken += has_second ? 12u : 6u;
  return max(best.x, best.y);
}

// The MIP of one ray over [t_near, t_far] (t_near jittered; t_entry before
// the jitter): the maximum of J through the window as a grey level.
vec3 mip_ray(vec3 eye, vec3 dir, vec3 inv_dir, float t_entry, float t_near, float t_far,
             float step, bool skipping, inout uint taken) {
  // Early termination: once the maximum reaches the window's white, no
  // later sample can change the pixel.
  bool early = has_flag(VPM_RAYCAST_EARLY_TERMINATION);
  RayPeaks peaks = RayPeaks(kNoValue, -1, kNoValue, -1);
  int k = 0;
  float black = p.window.x, white = p.window.z;
  BrickWalk w = walk_start(eye, dir, inv_dir, t_near);
  bool done = false;
  // The brightest brick first: its maximum raises the threshold the walk
  // below skips by, and reaching white ends the ray.
  if (skipping && has_flag(VPM_RAYCAST_BRIGHTEST_FIRST)) {
    BrickWalk bright;
    int k_bright;
    if (walk_to_brightest(w, black, white, t_near, t_far, step, bright, k_bright)) {
      done = mip_segment(k_bright, min(walk_exit(bright), t_far), t_near, step, eye, dir, early,
                         white, peaks, taken);
      g_sampled_brick = bright.b;
    }
  }
  // Segments: the samples of the next brick that can raise the maximum (and
  // show above the window); without skipping, the whole ray.
  for (float t_end;
       !done && next_segment(w, k, max(peaks.best, black), skipping, t_near, t_far, step, t_end);
       walk_step(w)) {
    done = mip_segment(k, t_end, t_near, step, eye, dir, early, white, peaks, taken);
    if (!skipping) break;
  }
  // The two peaks refined, where the ray took a sample and its maximum is
  // under white (early termination: white already); twelve reads. Also
  // under black: a ray that grazes the body samples air on both sides of a
  // thin rim, whose peak the search finds.
  float ray_max = peaks.best;
  if (has_flag(VPM_RAYCAST_PEAK_REFINE) && !done && peaks.k_best >= 0) {
    ray_max = refine_peaks(peaks, t_near, step, t_entry, t_far, eye, dir, taken);
  }
  return vec3(clamp((ray_max - p.window.x) * p.window.y, 0.0, 1.0));
}

#endif

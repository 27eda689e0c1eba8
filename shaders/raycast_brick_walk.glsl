// The brick walk of the ray caster (MIP and cell-gradient DVR), included by
// raycast_body.glsl after the globals and brick helpers it uses (g_bricks,
// g_brick_mm, brick_of, brick_linear, u_occupancy).
#ifndef VPM_RAYCAST_BRICK_WALK_GLSL
#define VPM_RAYCAST_BRICK_WALK_GLSL
// The brick walk (MIP and cell-gradient DVR): a 3D DDA over the brick grid
// along the ray. b: the brick the ray is in, entered at t_enter; t_next: the
// ray parameter of its next face per axis (the brick is left at the least).
// The ray is cut into segments, the samples of one occupied brick each,
// taken in an inner loop with no brick test; between segments the walk
// steps over empty bricks, and over bricks the ray crosses between two
// samples, one brick per iteration and no sample. On lavapipe every
// iteration pays for all the code of its loop body, so the brick code runs
// once per brick instead of once per sample (docs/RENDERING.md, "Empty-space
// skipping"). The CPU reference (raycast_cpu.cc) walks the same bricks with
// the same arithmetic.
struct BrickWalk {
  ivec3 b;
  vec3 t_next;
  float t_enter;
  ivec3 step_b;  // the sign of dir per axis
  vec3 t_delta;  // brick size / |dir| per axis: mm of ray per brick
};

// inv_dir: 1 / dir with no zero components (main), whose signs pick the faces.
BrickWalk walk_start(vec3 eye, vec3 dir, vec3 inv_dir, float t_near) {
  BrickWalk w;
  w.b = brick_of(eye + t_near * dir);
  vec3 face = vec3(w.b + ivec3(greaterThan(inv_dir, vec3(0.0)))) * g_brick_mm;
  w.t_next = (face - eye) * inv_dir;
  w.t_enter = t_near;
  w.step_b = ivec3(sign(inv_dir));
  w.t_delta = g_brick_mm * abs(inv_dir);
  return w;
}

float walk_exit(BrickWalk w) { return min(w.t_next.x, min(w.t_next.y, w.t_next.z)); }

// Into the next brick across the face the ray leaves by (x before y before
// z on a tie).
void walk_step(inout BrickWalk w) {
  bool ax = w.t_next.x <= w.t_next.y && w.t_next.x <= w.t_next.z;
  bool ay = !ax && w.t_next.y <= w.t_next.z;
  bvec3 m = bvec3(ax, ay, !ax && !ay);
  w.t_enter = walk_exit(w);
  w.b += ivec3(m) * w.step_b;
  w.t_next += vec3(m) * w.t_delta;
}

#ifdef VPM_RAYCAST_MIP
// The brick the MIP sampled first (walk_to_brightest), which the walk then
// treats as empty; far outside the grid when none.
ivec3 g_sampled_brick = ivec3(-(1 << 20));
#endif

// The occupancy of brick b (clamped to the grid); MIP: no value in the
// brick already sampled.
float brick_occupancy(ivec3 b) {
  float occ = texelFetch(u_occupancy, brick_linear(clamp(b, ivec3(0), g_bricks - 1))).r;
#ifdef VPM_RAYCAST_MIP
  if (b == g_sampled_brick) occ = kNoValue;
#endif
  return occ;
}

// True when the walk's brick, of occupancy occ, is above threshold and holds
// a sample (index >= k); then sets k to its first sample.
bool enter_brick(BrickWalk w, float occ, inout int k, float threshold, float t_near, float t_far,
                 float step) {
  int first = max(k, int(ceil((w.t_enter - t_near) / step)));
  float t_first = t_near + float(first) * step;
  if (t_first <= min(walk_exit(w), t_far) && occ > threshold) {
    k = first;
    return true;
  }
  return false;
}

// Walks on to the first brick that holds a sample (index >= k) and whose
// occupancy is above threshold; sets k to that brick's first sample. False
// when the ray ends first. Two bricks per iteration: both occupancy reads
// in flight at once, then the bricks tested in order, the same decisions as
// one brick at a time (docs/LAVAPIPE.md, "Two samples per iteration").
bool walk_to_occupied(inout BrickWalk w, inout int k, float threshold, float t_near,
                      float t_far, float step) {
  for (;;) {
    BrickWalk next = w;
    walk_step(next);
    float occ = brick_occupancy(w.b);
    float occ_next = brick_occupancy(next.b);
    if (w.t_enter > t_far) return false;
    if (enter_brick(w, occ, k, threshold, t_near, t_far, step)) return true;
    w = next;
    if (w.t_enter > t_far) return false;
    if (enter_brick(w, occ_next, k, threshold, t_near, t_far, step)) return true;
    walk_step(w);
  }
}


// Sample k of a segment that ends at t_end: x, and false once past the end.
bool segment_sample(int k, float t_near, float step, float t_end, vec3 eye, vec3 dir,
                    out vec3 x) {
  float t = t_near + float(k) * step;
  x = eye + t * dir;
  return t <= t_end;
}

// The next segment from sample k: with skipping, walks to the next brick
// that holds a sample and is above threshold, and the segment ends where
// the ray leaves it; without, the rest of the ray. Sets k to the segment's
// first sample and t_end; false when the ray has no sample left.
bool next_segment(inout BrickWalk w, inout int k, float threshold, bool skipping,
                  float t_near, float t_far, float step, out float t_end) {
  t_end = t_far;
  if (skipping) {
    if (!walk_to_occupied(w, k, threshold, t_near, t_far, step)) return false;
    t_end = min(walk_exit(w), t_far);
  }
  return t_near + float(k) * step <= t_end;
}

#endif

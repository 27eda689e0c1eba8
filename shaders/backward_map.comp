#version 450
#extension GL_GOOGLE_include_directive : require
// Rasterizes the owners of the backward map (shaders/backward_map.glsl,
// docs/WARP.md) tet by tet. Grid point g at p = g * step_mm belongs to the
// smallest-index tet whose barycentric weights at p, computed from its
// deformed positions, are all >= -eps; backward_map_write.comp then writes
// each point's value, (X(p) - p, 1) from its owner, or 0 where none.
//
// Passes (map_dims.w), one dispatch each, in this order:
//   0 clear  per moved tet, at its previous positions: the points it owned
//            get owner none (their values are rewritten by the write pass,
//            whose box holds the moved tets' previous boxes);
//   1 claim  per listed tet, its box now: atomicMin(owner, tet) at every
//            point it contains (no float atomics needed).
// A full rebuild fills owner with none (vkCmdFillBuffer), then runs 1 over
// all tets. An update runs 0 over the tets that moved (listed first, work.y
// of them) and 1 over those plus every unmoved tet whose box meets a moved
// tet's previous box (work.x in all): a point a moved tet owned may now
// belong to such a tet, any other point keeps its owner unless a moved tet
// now claims it with a smaller index, so the owners come out as in a full
// rebuild (docs/WARP.md has the argument).
//
// 16 lanes per listed tet (a tet of the 64^3 map spans some 20-40 rows;
// 64 lanes per tet left most of them idle and cost 1.3-2x the time of 16,
// measured with drag_loop_bench), 4 tets per workgroup (one tet per group
// cost lavapipe a group's set-up per tet: clear + claim 3.7-3.9 -> 3.5-3.6
// ms per drag step on the 1,326-vertex mesh); a tet's 16 lanes take the rows (y, z)
// of the tet's box in turn, and each row only the x range where the four
// weights, linear in x along the row, can be >= -eps (widened by one point;
// the per-point test decides). The clear pass walks the same ranges from the
// previous positions, so it visits every point the tet claimed then.
#include "shader_interface.glsl"

// kLanesPerTet lanes per tet, kTetsPerGroup tets per workgroup.
const uint kLanesPerTet = 16;
const uint kTetsPerGroup = 4;
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Tets { uvec4 tets[]; };
layout(std430, binding = 1) readonly buffer Deformed { vec4 deformed[]; };  // mm
layout(std430, binding = 2) readonly buffer Work { BackwardMapTetWork work[]; };
layout(std430, binding = 3) buffer Owner { uint owner[]; };
// The deformed positions of the previous update, mm.
layout(std430, binding = 4) readonly buffer Previous { vec4 previous[]; };
layout(push_constant) uniform Push { BackwardMapPush pc; };

const uint kNone = 0xFFFFFFFFu;
const int kClear = 0;
const int kClaim = 1;

uint grid_index(ivec3 g) {
  return uint(g.x) + uint(pc.map_dims.x) * (uint(g.y) + uint(pc.map_dims.y) * uint(g.z));
}

// The deformed tet: vertex 0 and the inverse of [d1-d0, d2-d0, d3-d0].
struct TetFrame {
  vec3 d0;
  mat3 inv;
  bool usable;  // false for a flat tet (zero or non-finite determinant)
};

vec3 corner(uint v, bool at_previous) { return at_previous ? previous[v].xyz : deformed[v].xyz; }

TetFrame tet_frame(uvec4 q, bool at_previous) {
  TetFrame f;
  f.d0 = corner(q.x, at_previous);
  mat3 m = mat3(corner(q.y, at_previous) - f.d0, corner(q.z, at_previous) - f.d0,
                corner(q.w, at_previous) - f.d0);
  float det = determinant(m);
  f.usable = det != 0.0 && !isnan(det) && !isinf(det);
  f.inv = f.usable ? inverse(m) : mat3(0.0);
  for (int c = 0; c < 3; ++c) {
    f.usable = f.usable && !any(isnan(f.inv[c])) && !any(isinf(f.inv[c]));
  }
  return f;
}

// Barycentric weights (w0, w1, w2, w3) of p_mm in the tet.
vec4 weights_at(TetFrame f, vec3 p_mm) {
  vec3 w = f.inv * (p_mm - f.d0);
  return vec4(1.0 - w.x - w.y - w.z, w);
}

// Inclusive x range of row (y, z) within [lo_x, hi_x] that can hold points
// with all weights >= -eps; empty when .x > .y.
ivec2 row_range(TetFrame f, int y, int z, int lo_x, int hi_x) {
  float eps = pc.step_mm.w;
  vec4 a = weights_at(f, vec3(0.0, float(y) * pc.step_mm.y, float(z) * pc.step_mm.z));
  vec3 b3 = f.inv[0] * pc.step_mm.x;  // d weights / d x (per grid step)
  vec4 b = vec4(-b3.x - b3.y - b3.z, b3);
  float lower = float(lo_x - 1);
  float upper = float(hi_x + 1);
  for (int i = 0; i < 4; ++i) {
    if (b[i] > 0.0) {
      lower = max(lower, (-eps - a[i]) / b[i]);
    } else if (b[i] < 0.0) {
      upper = min(upper, (-eps - a[i]) / b[i]);
    } else if (a[i] < -eps) {
      return ivec2(1, 0);
    }
  }
  lower = clamp(lower, float(lo_x - 1), float(hi_x + 1));
  upper = clamp(upper, float(lo_x - 1), float(hi_x + 1));
  return ivec2(max(int(ceil(lower)) - 1, lo_x), min(int(floor(upper)) + 1, hi_x));
}

void clear_row(uint t, int y, int z, ivec2 range) {
  for (int x = range.x; x <= range.y; ++x) {
    uint n = grid_index(ivec3(x, y, z));
    if (owner[n] == t) owner[n] = kNone;
  }
}

// The weights are linear along the row: evaluated at its first point, then
// stepped, which costs 4 multiply-adds per point and stays within float
// round-off of the direct formula (the steps are short, the weights of
// order 1).
void claim_row(uint t, TetFrame f, int y, int z, ivec2 range) {
  float eps = pc.step_mm.w;
  vec4 w0 = weights_at(f, vec3(range.x, y, z) * pc.step_mm.xyz);
  vec3 dw = f.inv[0] * pc.step_mm.x;
  vec4 step_w = vec4(-dw.x - dw.y - dw.z, dw);
  uint n0 = grid_index(ivec3(range.x, y, z));
  for (int i = 0; i <= range.y - range.x; ++i) {
    uint n = n0 + uint(i);
    vec4 w = w0 + float(i) * step_w;
    if (all(greaterThanEqual(w, vec4(-eps)))) atomicMin(owner[n], t);
  }
}

void main() {
  int pass = pc.map_dims.w;
  uint group = gl_WorkGroupID.x + gl_NumWorkGroups.x * gl_WorkGroupID.y;
  uint slot = group * kTetsPerGroup + gl_LocalInvocationID.x / kLanesPerTet;
  uint lane = gl_LocalInvocationID.x % kLanesPerTet;
  if (slot >= (pass == kClear ? pc.work.y : pc.work.x)) return;
  BackwardMapTetWork job = work[slot];
  uint t = uint(job.old_lo.w);
  ivec3 lo = pass == kClear ? job.old_lo.xyz : job.new_lo.xyz;
  ivec3 hi = pass == kClear ? job.old_hi.xyz : job.new_hi.xyz;
  if (any(greaterThan(lo, hi))) return;
  uvec4 q = tets[t];
  // A tet that was flat when claimed owns nothing to clear.
  TetFrame f = tet_frame(q, pass == kClear);
  if (!f.usable) return;
  uint rows_y = uint(hi.y - lo.y + 1);
  uint rows = rows_y * uint(hi.z - lo.z + 1);
  for (uint r = lane; r < rows; r += kLanesPerTet) {
    int y = lo.y + int(r % rows_y);
    int z = lo.z + int(r / rows_y);
    ivec2 range = row_range(f, y, z, lo.x, hi.x);
    if (pass == kClear) {
      clear_row(t, y, z, range);
    } else {
      claim_row(t, f, y, z, range);
    }
  }
}

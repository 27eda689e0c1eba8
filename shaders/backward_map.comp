#version 450
#extension GL_GOOGLE_include_directive : require
// Rasterizes the backward map (shaders/backward_map.glsl, docs/WARP.md) tet
// by tet. Grid point g at p = g * step_mm belongs to the smallest-index tet
// whose barycentric weights at p, computed from its deformed positions, are
// all >= -eps; its value is (sum_i w_i (rest_i - deformed_i), 1) = (X(p) - p,
// 1), and (0, 0, 0, 0) when no tet contains p.
//
// Passes (map_dims.w), one dispatch each, in this order:
//   0 reset  every grid point: owner none, value 0 (one invocation per point);
//   1 clear  per listed tet, its box from the previous update: the points it
//            owned get owner none and value 0;
//   2 claim  per listed tet, its box now: atomicMin(owner, tet) at every
//            point it contains (no float atomics needed);
//   3 write  per listed tet: the value at every point it owns.
// A full rebuild is 0, 2, 3 over all tets; an update is 1, 2, 3 over the
// tets that moved plus every tet whose box meets their old or new boxes
// (listed by the host), which gives the full rebuild's result exactly.
//
// One workgroup of 64 per listed tet; its invocations take the rows (y, z)
// of the tet's box in turn, and each row only the x range where the four
// weights, linear in x along the row, can be >= -eps (widened by one point;
// the per-point test decides).
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Tets { uvec4 tets[]; };
layout(std430, binding = 1) readonly buffer Deformed { vec4 deformed[]; };      // mm
layout(std430, binding = 2) readonly buffer RestOffset { vec4 rest_offset[]; };  // rest - deformed, mm
layout(std430, binding = 3) readonly buffer Work { BackwardMapTetWork work[]; };
layout(std430, binding = 4) buffer Owner { uint owner[]; };
layout(binding = 5, rgba32f) uniform writeonly image3D u_map;
layout(push_constant) uniform Push { BackwardMapPush pc; };

const uint kNone = 0xFFFFFFFFu;
const int kReset = 0;
const int kClear = 1;
const int kClaim = 2;
const int kWrite = 3;

uint grid_index(ivec3 g) {
  return uint(g.x) + uint(pc.map_dims.x) * (uint(g.y) + uint(pc.map_dims.y) * uint(g.z));
}

// The deformed tet: vertex 0 and the inverse of [d1-d0, d2-d0, d3-d0].
struct TetFrame {
  vec3 d0;
  mat3 inv;
  bool usable;  // false for a flat tet (zero or non-finite determinant)
};

TetFrame tet_frame(uvec4 q) {
  TetFrame f;
  f.d0 = deformed[q.x].xyz;
  mat3 m = mat3(deformed[q.y].xyz - f.d0, deformed[q.z].xyz - f.d0, deformed[q.w].xyz - f.d0);
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

void reset_point() {
  ivec3 g = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(g, pc.map_dims.xyz))) return;
  owner[grid_index(g)] = kNone;
  imageStore(u_map, g, vec4(0.0));
}

void clear_row(uint t, int y, int z, int lo_x, int hi_x) {
  for (int x = lo_x; x <= hi_x; ++x) {
    ivec3 g = ivec3(x, y, z);
    uint n = grid_index(g);
    if (owner[n] == t) {
      owner[n] = kNone;
      imageStore(u_map, g, vec4(0.0));
    }
  }
}

void claim_or_write_row(int pass, uint t, uvec4 q, TetFrame f, int y, int z, ivec2 range) {
  float eps = pc.step_mm.w;
  for (int x = range.x; x <= range.y; ++x) {
    ivec3 g = ivec3(x, y, z);
    uint n = grid_index(g);
    vec3 p = vec3(g) * pc.step_mm.xyz;
    if (pass == kClaim) {
      vec4 w = weights_at(f, p);
      if (all(greaterThanEqual(w, vec4(-eps)))) atomicMin(owner[n], t);
    } else if (owner[n] == t) {
      vec4 w = weights_at(f, p);
      vec3 d = w.x * rest_offset[q.x].xyz + w.y * rest_offset[q.y].xyz +
               w.z * rest_offset[q.z].xyz + w.w * rest_offset[q.w].xyz;
      imageStore(u_map, g, vec4(d, 1.0));
    }
  }
}

void main() {
  int pass = pc.map_dims.w;
  if (pass == kReset) {
    reset_point();
    return;
  }
  uint slot = gl_WorkGroupID.x + gl_NumWorkGroups.x * gl_WorkGroupID.y;
  if (slot >= pc.work.x) return;
  BackwardMapTetWork job = work[slot];
  uint t = uint(job.old_lo.w);
  ivec3 lo = pass == kClear ? job.old_lo.xyz : job.new_lo.xyz;
  ivec3 hi = pass == kClear ? job.old_hi.xyz : job.new_hi.xyz;
  if (any(greaterThan(lo, hi))) return;
  uvec4 q = tets[t];
  TetFrame f;
  if (pass != kClear) {
    f = tet_frame(q);
    if (!f.usable) return;
  }
  uint rows_y = uint(hi.y - lo.y + 1);
  uint rows = rows_y * uint(hi.z - lo.z + 1);
  for (uint r = gl_LocalInvocationID.x; r < rows; r += gl_WorkGroupSize.x) {
    int y = lo.y + int(r % rows_y);
    int z = lo.z + int(r / rows_y);
    if (pass == kClear) {
      clear_row(t, y, z, lo.x, hi.x);
    } else {
      claim_or_write_row(pass, t, q, f, y, z, row_range(f, y, z, lo.x, hi.x));
    }
  }
}

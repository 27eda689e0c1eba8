#version 450
#extension GL_GOOGLE_include_directive : require
// Per brick of the DEFORMED space: which source values its samples can see.
// A sample at x reads I at X(x) = x + d(x), d trilinear in the backward map,
// so over the brick d lies within the per-axis min and max of d at the map
// grid points of the cells the brick overlaps. The source region reachable
// is the brick dilated by that range; the value range is the union of the
// source bricks' min-max over it. DVR writes 1 when the lookup table has any
// non-zero opacity over that range, else 0; MIP writes the range's max.
// Without a map the dilation is 0 and each brick sees only itself.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer MinMax { vec2 minmax[]; };
layout(binding = 1) uniform samplerBuffer u_map;  // RGBA32F grid points, x fastest
layout(std430, binding = 2) readonly buffer Prefix { int nonzero_prefix[]; };
layout(std430, binding = 3) writeonly buffer Occupancy { float occupancy[]; };
layout(push_constant) uniform Push { BrickOccupancyPush pc; };

void main() {
  ivec3 nb = pc.bricks.xyz;
  // The pass covers the box of bricks from pc.box_lo.xyz (all bricks, or
  // those whose map cells a map update changed).
  ivec3 box = ivec3(pc.flags.zw, pc.box_lo.w);
  int local = int(gl_GlobalInvocationID.x);
  if (local >= box.x * box.y * box.z) return;
  ivec3 b = pc.box_lo.xyz + ivec3(local % box.x, (local / box.x) % box.y, local / (box.x * box.y));
  int index = b.x + nb.x * (b.y + nb.y * b.z);
  ivec3 n = pc.dims.xyz;
  vec3 s = pc.spacing_mm.xyz;
  ivec3 w = pc.brick_voxels.xyz;
  vec3 lo_mm = vec3(b * w) * s;
  vec3 hi_mm = vec3(min((b + 1) * w, n - 1)) * s;
  vec3 dmin = vec3(0.0), dmax = vec3(0.0);
  if (pc.flags.y != 0) {
    ivec3 m = ivec3(pc.map_dims.xyz);
    vec3 to_grid = vec3(m - 1) / (vec3(n - 1) * s);
    ivec3 g_lo = clamp(ivec3(floor(lo_mm * to_grid)), ivec3(0), m - 1);
    ivec3 g_hi = clamp(ivec3(floor(hi_mm * to_grid)) + 1, ivec3(0), m - 1);
    dmin = vec3(3.0e38);
    dmax = vec3(-3.0e38);
    for (int z = g_lo.z; z <= g_hi.z; ++z)
      for (int y = g_lo.y; y <= g_hi.y; ++y)
        for (int x = g_lo.x; x <= g_hi.x; ++x) {
          vec3 d = texelFetch(u_map, x + m.x * (y + m.y * z)).xyz;
          dmin = min(dmin, d);
          dmax = max(dmax, d);
        }
  }
  // Source indices the brick's samples reach, u in [u_lo, u_hi] (voxels);
  // a trilinear read at u takes voxels floor(u) .. ceil(u) with non-zero
  // weight, so the source bricks covering voxels floor(u_lo) .. ceil(u_hi)
  // (brick s covers [w s, w s + w] per axis) hold every value a sample can take.
  // Without displacement u_hi is the brick's own upper face: its own
  // source brick suffices, not the next one as well.
  vec3 u_lo = clamp(vec3(b * w) + dmin / s, vec3(0.0), vec3(n - 1));
  vec3 u_hi = clamp(vec3(min((b + 1) * w, n - 1)) + dmax / s, vec3(0.0), vec3(n - 1));
  ivec3 s_lo = clamp(ivec3(floor(u_lo / vec3(w))), ivec3(0), nb - 1);
  ivec3 s_hi = clamp(ivec3(ceil(u_hi / vec3(w))) - 1, s_lo, nb - 1);
  float vmin = 3.0e38, vmax = -3.0e38;
  for (int z = s_lo.z; z <= s_hi.z; ++z)
    for (int y = s_lo.y; y <= s_hi.y; ++y)
      for (int x = s_lo.x; x <= s_hi.x; ++x) {
        vec2 r = minmax[x + nb.x * (y + nb.y * z)];
        vmin = min(vmin, r.x);
        vmax = max(vmax, r.y);
      }
  if (pc.flags.x == 1) {
    occupancy[index] = vmax;
    return;
  }
  int entries = int(pc.lut.z);
  float f_lo = clamp((vmin - pc.lut.x) * pc.lut.y, 0.0, float(entries - 1));
  float f_hi = clamp((vmax - pc.lut.x) * pc.lut.y, 0.0, float(entries - 1));
  int e_lo = min(int(f_lo), entries - 2);
  int e_hi = min(int(f_hi) + 1, entries - 1);
  occupancy[index] = nonzero_prefix[e_hi + 1] - nonzero_prefix[e_lo] > 0 ? 1.0 : 0.0;
}

#version 450
#extension GL_GOOGLE_include_directive : require
// The write pass of the backward map (docs/WARP.md): one invocation per grid
// point of a box (pc.box_lo..box_hi, inclusive; the whole grid on a full
// rebuild, else the box whose owners may have changed). It reads the owner
// that backward_map.comp's claim pass left at the point and writes
// (X(p) - p, 1) from the owner's affine frame, or (0, 0, 0, 0) where no tet
// owns the point. Inside a tet X(p) - p = sum_i w_i(p) (rest_i - deformed_i)
// is affine in p: the host gives each tet (d0 = deformed vertex 0, o0 = rest0
// - deformed0, A = [o1 - o0, o2 - o0, o3 - o0] [d1 - d0, d2 - d0, d3 - d0]^-1,
// composed in double) as 4 vec4, and the value is o0 + A (p - d0).
//
// Per point instead of per tet: the previous write pass walked every listed
// tet's rows again (12 ms of a 22 ms map update for 2321 tets, 64^3 points);
// this reads one owner and one frame per point, no row search, and points
// outside every tet need no separate clear (they get 0 here).
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Owner { uint owner[]; };
// Per tet 4 vec4: (d0 mm, 0), (A row 0, o0.x), (A row 1, o0.y), (A row 2, o0.z).
layout(std430, binding = 1) readonly buffer Frames { vec4 frames[]; };
// The map values, x fastest, map_dims.w points per slab.
layout(std430, binding = 2) writeonly buffer Values0 { vec4 values0[]; };
layout(std430, binding = 3) writeonly buffer Values1 { vec4 values1[]; };
layout(std430, binding = 4) writeonly buffer Values2 { vec4 values2[]; };
layout(std430, binding = 5) writeonly buffer Values3 { vec4 values3[]; };
layout(push_constant) uniform Push { BackwardMapWritePush pc; };

const uint kNone = 0xFFFFFFFFu;

void store_value(uint n, vec4 value) {
  uint slab = uint(pc.map_dims.w);
  if (n < slab) {
    values0[n] = value;
  } else if (n < 2u * slab) {
    values1[n - slab] = value;
  } else if (n < 3u * slab) {
    values2[n - 2u * slab] = value;
  } else {
    values3[n - 3u * slab] = value;
  }
}

void main() {
  uvec3 size = uvec3(pc.box_hi.xyz - pc.box_lo.xyz + 1);
  uint i = gl_GlobalInvocationID.x + gl_NumWorkGroups.x * gl_WorkGroupSize.x * gl_WorkGroupID.y;
  if (i >= size.x * size.y * size.z) return;
  ivec3 g = pc.box_lo.xyz + ivec3(i % size.x, (i / size.x) % size.y, i / (size.x * size.y));
  uint n = uint(g.x) + uint(pc.map_dims.x) * (uint(g.y) + uint(pc.map_dims.y) * uint(g.z));
  uint t = owner[n];
  vec4 value = vec4(0.0);
  if (t != kNone) {
    vec4 f0 = frames[4u * t];
    vec4 f1 = frames[4u * t + 1u];
    vec4 f2 = frames[4u * t + 2u];
    vec4 f3 = frames[4u * t + 3u];
    vec3 r = vec3(g) * pc.step_mm.xyz - f0.xyz;
    value = vec4(dot(f1.xyz, r) + f1.w, dot(f2.xyz, r) + f2.w, dot(f3.xyz, r) + f3.w, 1.0);
  }
  store_value(n, value);
}

// The ray caster: one invocation per pixel, 8x8 per workgroup. Compiled in
// eight variants, one small raycast_*.comp each, chosen by defines:
//   VPM_RAYCAST_MIP      MIP (else DVR)
//   VPM_RAYCAST_MAP      sample through the backward map (else identity)
//   VPM_RAYCAST_SAMPLED  volume and map from sampler3Ds with hardware
//                        trilinear filtering (the map through
//                        backward_map.glsl's rest_position); else both from
//                        uniform texel buffers with manual trilinear (the map
//                        copied there by VolumeRenderer): faster on lavapipe,
//                        docs/RENDERING.md
// Mode and map are compile-time because lavapipe runs both sides of every
// branch under a lane mask: a runtime `if (mip)` or `if (has_map)` costs the
// untaken side too. For the same reason the loop body reads the volume at
// exactly one place: a sample that needs shading spends the next six
// iterations on its six gradient taps (a small state machine) instead of
// making six more reads that every other iteration would pay for as well.
//
// Per ray: intersect the image box [0, extent_mm]; samples at
// t_k = t_near + k * step (t_near moved on by a jitter in [0, step) when
// VPM_RAYCAST_JITTER is set: ray_jitter.glsl); each reads the deformed volume J(x) = I(X(x)), X
// from the backward map (the brick-walk loops read two samples per
// iteration, docs/RENDERING.md). Bricks of wx x wy x wz cells (p.brick_voxels: about
// 6 mm still, 12 mm interactive, whatever the spacing) that the occupancy pass marked
// empty (DVR: zero opacity over every value the brick can show; MIP: nothing
// above the running maximum or the window's black) are jumped over to the
// first sample grid point past them, so skipping never moves a sample. DVR
// composites front to back with opacities from the step-corrected table,
// shaded by a Blinn-Phong headlight on the gradient of J (central
// differences, one spacing, 6 taps of J; samples weighing under 1/256 in the
// pixel are lit head-on), and stops at opacity > 0.99; MIP stops at the
// window's white and refines the peaks around its two brightest samples
// (raycast_mip.glsl).
// Specialization constant 0 (kCellGradient, DVR): shade with the analytic
// gradient of the trilinear cells a sample already reads (the source's 8
// voxels, the map's 8 points: the chain rule through the map), no taps and
// no state machine; interactive and still DVR frames use it by default
// (docs/RENDERING.md, "Quality modes"). A constant, so the pipeline keeps
// one loop only.
// The CPU reference, server/raycast/raycast_cpu.cc, mirrors every step.
#ifndef VPM_RAYCAST_BODY_GLSL
#define VPM_RAYCAST_BODY_GLSL

#include "shader_interface.glsl"
#include "backward_map.glsl"
#include "ray_jitter.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
#ifdef VPM_RAYCAST_SAMPLED
layout(binding = 0) uniform sampler3D u_volume;
layout(binding = 1) uniform sampler3D u_map;
#include "voxel_encoding.glsl"
#else
layout(binding = 0) uniform isamplerBuffer u_volume;  // R32_SINT, volume_access.glsl
layout(binding = 1) uniform samplerBuffer u_map;  // RGBA32F, grid points x fastest
#include "volume_access.glsl"
#endif
// A storage buffer, not a uniform block: lavapipe 22.3 inlines uniform-block
// values that steer branches into a freshly compiled shader at every
// descriptor bind, and never frees it (docs/SERVICE.md, "Memory findings");
// storage-buffer loads are not inlined.
layout(std140, binding = 2) restrict readonly buffer Params { RaycastParams p; };
// The baked table (RenderLutBlock: VPM_RENDER_LUT_ENTRIES RGBA entries) as a
// uniform texel buffer: lavapipe gathers it; indexed per sample in a uniform
// block it cost the composite still 7-10% more (docs/RENDERING.md).
layout(binding = 3) uniform samplerBuffer u_lut;
// Per brick (R32F), as a uniform texel buffer: one gather per fetch on
// lavapipe.
layout(binding = 4) uniform samplerBuffer u_occupancy;
layout(std430, binding = 5) writeonly buffer Pixels { uint pixels[]; };
layout(std430, binding = 6) buffer Stats { uint samples_taken; };

layout(constant_id = 0) const bool kCellGradient = false;
// Specialization constant 3 (with kCellGradient, DVR; 1, 2 and 4 are
// voxel_encoding.glsl's): composite each step as a segment through the
// pre-integrated table (server/raycast/preintegrated_lut.h), which follows
// the 1D table in u_lut.
layout(constant_id = 3) const bool kPreintegrated = false;
// Which rows of tiles this dispatch casts: a still frame is cast in bands.
layout(push_constant) uniform Band { RaycastBandPush band; };

const float kOpaque = 0.99;
// A sample whose weight in the pixel, (1 - A) a, is under 1/256 is not worth
// six taps: it is lit head-on (ambient + diffuse), as flat tissue is.
const float kShadeMinWeight = 1.0 / 256.0;
const float kNoValue = -3.0e38;
// The cell-gradient loops' threshold: weight under 1/256 per mm of ray
// (kShadeMinWeight x step / 1 mm), so that the share of the picture lit
// head-on does not grow as the step shrinks (docs/RENDERING.md, "Sampling").
float g_shade_min_weight;

bool has_flag(int f) { return (p.image.z & f) != 0; }

// Set once per invocation (set_globals), so that the sample loop neither
// reloads the parameter buffer nor divides: the same values and operations
// as computing them in place, so the same results.
vec3 g_inv_spacing;  // 1/mm
vec3 g_inv_brick;    // 1 / brick size (mm)
vec3 g_extent_mm;    // the image box, (n - 1) * spacing, mm
vec3 g_last_index;   // n - 1, voxels
ivec3 g_dims;        // n, voxels
ivec3 g_bricks;      // brick grid
vec3 g_brick_mm;     // brick size, mm
vec3 g_map_last;     // M - 1, map grid points
ivec3 g_map_dims;    // M, map grid points
vec3 g_to_grid;      // (M - 1) / extent: map grid points per mm
vec4 g_lut;          // p.lut
vec4 g_shading;      // p.shading
float g_gradient_half;  // p.gradient.x, value/mm
float g_pre_scale;      // pre-integrated entries per value unit
float g_light_both_ends;  // 1 with VPM_RAYCAST_LIGHT_BOTH_ENDS, else 0

void set_globals() {
  g_inv_spacing = 1.0 / p.spacing_mm.xyz;
  g_inv_brick = 1.0 / (p.spacing_mm.xyz * vec3(p.brick_voxels.xyz));
  g_extent_mm = vec3(p.dims.xyz - 1) * p.spacing_mm.xyz;
  g_last_index = vec3(p.dims.xyz - 1);
  g_dims = p.dims.xyz;
  g_bricks = p.bricks.xyz;
  g_brick_mm = p.spacing_mm.xyz * vec3(p.brick_voxels.xyz);
  g_map_last = p.map_dims.xyz - 1.0;
  g_map_dims = ivec3(p.map_dims.xyz);
  g_to_grid = g_map_last / g_extent_mm;
  g_lut = p.lut;
  g_shading = p.shading;
  g_gradient_half = p.gradient.x;
  g_pre_scale = g_lut.y * (g_lut.w - 1.0) / (g_lut.z - 1.0);
  g_light_both_ends = (p.image.z & VPM_RAYCAST_LIGHT_BOTH_ENDS) != 0 ? 1.0 : 0.0;
}

vec3 extent_mm() { return g_extent_mm; }

// Trilinear interpolation of the corners c000..c111 (locals of type T, x
// fastest) at the fraction f of the cell, in the order x, y, z, each lerp
// a + (b - a) * f, as the CPU reference: VPM_TRILINEAR_XY declares the x
// lerps c00..c11 and the y lerps c0, c1 (the value is c0 + (c1 - c0) * f.z);
// VPM_TRILINEAR_WITH_DERIVATIVES also gives the derivatives per unit of
// f.x, f.y, f.z. Macros serve the volume's floats and the map's vec3s alike.
#define VPM_TRILINEAR_XY(T, f)                \
  T c00 = c000 + (c100 - c000) * f.x;         \
  T c10 = c010 + (c110 - c010) * f.x;         \
  T c01 = c001 + (c101 - c001) * f.x;         \
  T c11 = c011 + (c111 - c011) * f.x;         \
  T c0 = c00 + (c10 - c00) * f.y;             \
  T c1 = c01 + (c11 - c01) * f.y

// The 8 corners c000..c111 of the cell at linear index `base` of a texel
// buffer with x stride 1, y stride sy, z stride sz; SW picks the channels.
#define VPM_FETCH_CELL(T, tex, SW)                       \
  T c000 = texelFetch(tex, base).SW;                     \
  T c100 = texelFetch(tex, base + 1).SW;                 \
  T c010 = texelFetch(tex, base + sy).SW;                \
  T c110 = texelFetch(tex, base + sy + 1).SW;            \
  T c001 = texelFetch(tex, base + sz).SW;                \
  T c101 = texelFetch(tex, base + sz + 1).SW;            \
  T c011 = texelFetch(tex, base + sz + sy).SW;           \
  T c111 = texelFetch(tex, base + sz + sy + 1).SW

// The same 8 voxel corners of the cell at i0 of the volume (n voxels), as
// the x-edges' 4 pairs of volume_access.glsl's voxel_pair (one fetch each
// where the volume is held in pairs: docs/LAVAPIPE.md, "Volumes through
// uniform texel buffers").
#define VPM_FETCH_VOXEL_CELL(n, i0)                                   \
  int base = i0.x + n.x * i0.y + n.x * n.y * i0.z;                    \
  vec2 e00 = voxel_pair(base);                                        \
  vec2 e10 = voxel_pair(base + n.x);                                  \
  vec2 e01 = voxel_pair(base + n.x * n.y);                            \
  vec2 e11 = voxel_pair(base + n.x * n.y + n.x);                      \
  float c000 = e00.x, c100 = e00.y;                                   \
  float c010 = e10.x, c110 = e10.y;                                   \
  float c001 = e01.x, c101 = e01.y;                                   \
  float c011 = e11.x, c111 = e11.y

// The same corners through a per-point fetch function (fetch(ivec3 index)).
#define VPM_FETCH_CELL_AT(T, fetch, i0)                  \
  T c000 = fetch(i0);                                    \
  T c100 = fetch(i0 + ivec3(1, 0, 0));                   \
  T c010 = fetch(i0 + ivec3(0, 1, 0));                   \
  T c110 = fetch(i0 + ivec3(1, 1, 0));                   \
  T c001 = fetch(i0 + ivec3(0, 0, 1));                   \
  T c101 = fetch(i0 + ivec3(1, 0, 1));                   \
  T c011 = fetch(i0 + ivec3(0, 1, 1));                   \
  T c111 = fetch(i0 + ivec3(1, 1, 1))

#define VPM_TRILINEAR_WITH_DERIVATIVES(T, f, value, d_fx, d_fy, d_fz)          \
  {                                                                            \
    VPM_TRILINEAR_XY(T, f);                                                    \
    T dx0 = (c100 - c000) + ((c110 - c010) - (c100 - c000)) * f.y;             \
    T dx1 = (c101 - c001) + ((c111 - c011) - (c101 - c001)) * f.y;             \
    T dy0 = c10 - c00;                                                         \
    T dy1 = c11 - c01;                                                         \
    value = c0 + (c1 - c0) * f.z;                                              \
    d_fx = dx0 + (dx1 - dx0) * f.z;                                            \
    d_fy = dy0 + (dy1 - dy0) * f.z;                                            \
    d_fz = c1 - c0;                                                            \
  }

// I at continuous index u in [0, n - 1].
float source_at(vec3 u) {
#ifdef VPM_RAYCAST_SAMPLED
  return decode_image_voxel(textureLod(u_volume, (u + 0.5) / vec3(p.dims.xyz), 0.0).r);
#else
  // Lerps in the order x, y, z, each a + (b - a) * f, as the CPU reference.
  ivec3 n = g_dims;
  ivec3 i0 = min(ivec3(floor(u)), n - 2);
  vec3 f = u - vec3(i0);
  VPM_FETCH_VOXEL_CELL(n, i0);
  VPM_TRILINEAR_XY(float, f);
  return c0 + (c1 - c0) * f.z;
#endif
}

#if defined(VPM_RAYCAST_MAP) && !defined(VPM_RAYCAST_SAMPLED)
// X(x) from the map's texel copy: what rest_position() computes through
// the sampler (grid point a at a * extent / (M - 1), clamped to the edge),
// with exact weights; lerps in the order x, y, z as the CPU reference.
vec3 rest_from_texels(vec3 x) {
  vec3 gc = clamp(x / g_extent_mm * g_map_last, vec3(0.0), g_map_last);
  ivec3 mi = g_map_dims;
  ivec3 i0 = min(ivec3(floor(gc)), mi - 2);
  vec3 f = gc - vec3(i0);
  int sy = mi.x, sz = mi.x * mi.y;
  int base = i0.x + sy * i0.y + sz * i0.z;
  VPM_FETCH_CELL(vec3, u_map, xyz);
  VPM_TRILINEAR_XY(vec3, f);
  return x + (c0 + (c1 - c0) * f.z);
}
#endif

// J(x): the source at the rest position of x (mm), clamped to the box.
float deformed_value(vec3 x) {
#if defined(VPM_RAYCAST_MAP) && defined(VPM_RAYCAST_SAMPLED)
  vec3 rest = rest_position(u_map, x, extent_mm(), p.map_dims.xyz);
#elif defined(VPM_RAYCAST_MAP)
  vec3 rest = rest_from_texels(x);
#else
  vec3 rest = x;
#endif
  return source_at(clamp(rest * g_inv_spacing, vec3(0.0), g_last_index));
}

// Texels for the cell gradient: volume voxel i of the 3D image (the texel
// buffer's cells are read in pairs, VPM_FETCH_VOXEL_CELL), map point g
// (displacement).
#ifdef VPM_RAYCAST_SAMPLED
float volume_texel(ivec3 i) { return decode_image_voxel(texelFetch(u_volume, i, 0).r); }
#endif

#ifdef VPM_RAYCAST_MAP
vec3 map_texel(ivec3 g) {
  ivec3 m = g_map_dims;
#ifdef VPM_RAYCAST_SAMPLED
  return texelFetch(u_map, g, 0).xyz;
#else
  return texelFetch(u_map, g.x + m.x * (g.y + m.y * g.z)).xyz;
#endif
}
#endif

// I at continuous index u (the lerps of source_at) and, in grad_u, its
// gradient per voxel: the derivative of the trilinear interpolant of the
// cell holding u.
float source_and_gradient(vec3 u, out vec3 grad_u) {
  ivec3 n = g_dims;
  ivec3 i0 = min(ivec3(floor(u)), n - 2);
  vec3 f = u - vec3(i0);
#ifdef VPM_RAYCAST_SAMPLED
  VPM_FETCH_CELL_AT(float, volume_texel, i0);
#else
  VPM_FETCH_VOXEL_CELL(n, i0);
#endif
  float value, d_fx, d_fy, d_fz;
  VPM_TRILINEAR_WITH_DERIVATIVES(float, f, value, d_fx, d_fy, d_fz);
  grad_u = vec3(d_fx, d_fy, d_fz);
  return value;
}

// J(x) and its gradient (value/mm) by the chain rule: grad J(x) =
// (1 + dd/dx)^T grad I(X(x)), with dd/dx that of the trilinear map cell.
// The clamps at the box's faces are not differentiated.
float deformed_value_and_gradient(vec3 x, out vec3 grad) {
  vec3 rest = x;
  mat3 jacobian = mat3(1.0);  // d rest / d x, columns per x axis
#ifdef VPM_RAYCAST_MAP
  vec3 to_grid = g_to_grid;
  vec3 gc = clamp(x * to_grid, vec3(0.0), g_map_last);
  ivec3 mi = g_map_dims;
  ivec3 i0 = min(ivec3(floor(gc)), mi - 2);
  vec3 f = gc - vec3(i0);
  VPM_FETCH_CELL_AT(vec3, map_texel, i0);
  vec3 offset, d_fx, d_fy, d_fz;
  VPM_TRILINEAR_WITH_DERIVATIVES(vec3, f, offset, d_fx, d_fy, d_fz);
  rest = x + offset;
  jacobian[0] += d_fx * to_grid.x;
  jacobian[1] += d_fy * to_grid.y;
  jacobian[2] += d_fz * to_grid.z;
#endif
  vec3 grad_u;
  float v = source_and_gradient(clamp(rest * g_inv_spacing, vec3(0.0), g_last_index),
                                grad_u);
  vec3 grad_rest = grad_u * g_inv_spacing;
  grad = vec3(dot(jacobian[0], grad_rest), dot(jacobian[1], grad_rest),
              dot(jacobian[2], grad_rest));
  return v;
}

ivec3 brick_of(vec3 x) { return clamp(ivec3(floor(x * g_inv_brick)), ivec3(0), g_bricks - 1); }

// Linear index of brick b of the grid (x fastest).
int brick_linear(ivec3 b) { return b.x + g_bricks.x * (b.y + g_bricks.y * b.z); }

int brick_index(vec3 x) { return brick_linear(brick_of(x)); }

// Ray parameter where the ray leaves the brick holding x.
float brick_exit(vec3 x, vec3 eye, vec3 inv_dir) {
  vec3 size = g_brick_mm;
  ivec3 b = brick_of(x);
  vec3 lo = vec3(b) * size;
  vec3 hi = min(vec3(b + 1) * size, extent_mm());
  vec3 bound = mix(lo, hi, greaterThan(inv_dir, vec3(0.0)));
  vec3 t = (bound - eye) * inv_dir;
  return min(t.x, min(t.y, t.z));
}

// First sample index past t_exit (at least k + 1).
int next_sample(float t_exit, float t_near, float step, int k) {
  return max(k + 1, int(floor((t_exit - t_near) / step)) + 1);
}

// Jumps over bricks whose occupancy is <= threshold, in a loop of its own
// that takes no sample: moves sample k (at t along the ray, point x) to the
// first sample in a brick above the threshold, or past t_far.
void skip_empty_bricks(inout int k, inout float t, inout vec3 x, float threshold, vec3 eye,
                       vec3 dir, vec3 inv_dir, float t_near, float t_far, float step) {
  while (t <= t_far && texelFetch(u_occupancy, brick_index(x)).r <= threshold) {
    k = next_sample(brick_exit(x, eye, inv_dir), t_near, step, k);
    t = t_near + float(k) * step;
    x = eye + t * dir;
  }
}

#include "raycast_brick_walk.glsl"
#ifdef VPM_RAYCAST_MIP
#include "raycast_mip.glsl"
#endif

vec4 lut_at(float v) {
  float n = g_lut.z;
  float f = clamp((v - g_lut.x) * g_lut.y, 0.0, n - 1.0);
  int i = min(int(f), int(n) - 2);
  float t = f - float(i);
  vec4 a = texelFetch(u_lut, i);
  vec4 b = texelFetch(u_lut, i + 1);
  return a + (b - a) * t;
}

// Blinn-Phong with the light at the eye: the half vector is the view
// vector, so specular is |n.l|^shininess, here by Schlick's rational
// approximation x / (n - n x + x) (one division; lavapipe pays for this
// function on every iteration, see above); two-sided (|n.l|). g: the
// gradient (value/mm). Shading is weighted by s = |g| / (|g| + g_half), so
// that inside homogeneous tissue, where the gradient is noise, the colour
// stays as lit head-on instead of speckling. Returns (ambient + diffuse
// factor, specular term), which lit_by applies to a colour.
vec2 light_factors(vec3 g, vec3 dir) {
  float len = length(g);
  float ndl = len > 0.0 ? abs(dot(g, dir)) / len : 1.0;
  float s = len / (len + g_gradient_half);
  float n = g_shading.w;
  float spec = ndl / (n - n * ndl + ndl);
  float diffuse = 1.0 + (ndl - 1.0) * s;
  return vec2(g_shading.x + g_shading.y * diffuse, g_shading.z * spec * s);
}

// alpha: 1 for a colour, the opacity for a premultiplied one (the
// specular highlight and the clamp scale with it).
vec3 lit_by(vec3 rgb, vec2 light, float alpha) {
  return min(rgb * light.x + vec3(alpha * light.y), vec3(alpha));
}

vec3 shade(vec3 rgb, vec3 g, vec3 dir, float alpha) {
  return lit_by(rgb, light_factors(g, dir), alpha);
}

// The pre-integrated table at (front, back) values, bilinear: premultiplied
// colour and opacity of one step (SamplePreintegratedLut on the CPU).
vec4 preintegrated_at(float front, float back) {
  float n = g_lut.w;
  float ff = clamp((front - g_lut.x) * g_pre_scale, 0.0, n - 1.0);
  float fb = clamp((back - g_lut.x) * g_pre_scale, 0.0, n - 1.0);
  int i = min(int(ff), int(n) - 2);
  int j = min(int(fb), int(n) - 2);
  float s = ff - float(i), t = fb - float(j);
  int base = VPM_RENDER_LUT_ENTRIES + i + int(n) * j;
  vec4 a = texelFetch(u_lut, base);
  vec4 b = texelFetch(u_lut, base + 1);
  vec4 c = texelFetch(u_lut, base + int(n));
  vec4 d = texelFetch(u_lut, base + int(n) + 1);
  vec4 ab = a + (b - a) * s;
  vec4 cd = c + (d - c) * s;
  return ab + (cd - ab) * t;
}

// The ray parameter of the last sample t_near + k step at or before t_far
// (t_near <= t_far), by the same arithmetic as the loops' test.
float last_sample_t(float t_near, float t_far, float step) {
  float k = floor((t_far - t_near) / step);
  if (t_near + (k + 1.0) * step <= t_far) k += 1.0;
  if (k > 0.0 && t_near + k * step > t_far) k -= 1.0;
  return t_near + k * step;
}

// Early termination (docs/RENDERING.md, "Ray casting", item 5): once the
// opacity passes kOpaque, the transmittance left (under 1%) takes the last
// step's own colour, rgb / over (over: its opacity when rgb is
// premultiplied, else 1), as if the ray went on through the same material;
// left to the background, how much of it shows would depend on where the
// last step happens to land. The division is in the branch that ends the
// ray: every sample pays for what stands outside it. True when the ray ends.
bool ends_opaque(bool early, vec3 rgb, float over, inout vec4 acc) {
  if (!early || acc.a <= kOpaque) return false;
  acc.rgb += (1.0 - acc.a) * (rgb / over);
  acc.a = 1.0;
  return true;
}

// Composites a step c (premultiplied colour and opacity, from the
// pre-integrated table) that ends at a sample of gradient g, as
// composite_sample does a point. The step is lit by the mean of its two
// ends' light_factors (the trapezoid rule; docs/RENDERING.md, "Sampling"):
// light_front holds the front's (xy) and whether it is known (z: 1; never
// without VPM_RAYCAST_LIGHT_BOTH_ENDS), and takes this step's back's; a step
// whose weight in the pixel is under min_weight is lit head-on. True when
// early termination ends the ray.
bool composite_step(vec4 c, vec3 g, float min_weight, vec3 dir, bool shading, bool early,
                    inout vec3 light_front, inout vec4 acc) {
  float transmitted = 1.0 - acc.a;
  if (shading) {
    vec2 light = light_factors(g, dir);
    vec2 seg = light_front.z > 0.0 ? 0.5 * (light + light_front.xy) : light;
    light_front = vec3(light, g_light_both_ends);
    c.rgb = transmitted * c.a > min_weight ? lit_by(c.rgb, seg, c.a)
                                           : min(c.rgb * (g_shading.x + g_shading.y), vec3(c.a));
  }
  if (c.a > 0.0) {
    acc.rgb += transmitted * c.rgb;
    acc.a += transmitted * c.a;
    return ends_opaque(early, c.rgb, c.a, acc);
  }
  return false;
}

// The whole step from a sample of value `front` to one of value `back`.
bool composite_segment(float front, float back, vec3 g, vec3 dir, bool shading, bool early,
                       inout vec3 light_front, inout vec4 acc) {
  return composite_step(preintegrated_at(front, back), g, g_shade_min_weight, dir, shading,
                        early, light_front, acc);
}

// A ray's partial end step (VPM_RAYCAST_PARTIAL_END_STEPS) from x_front to
// x_back, `fraction` (clamped to [0, 1]) of a step long: the table's step
// between their values, shortened as a step of constant value would be
// (PartialPreintegratedStep in preintegrated_lut.h), and lit by x_back's
// light alone, as a step after skipped bricks (lit at both ends, the kidney
// CT's stills with the view cut were up to 6.4 dB further from step / 8:
// docs/RENDERING.md, "Sampling"); its shading threshold is shortened with
// it. Two reads. front: x_back's value. True when early termination ends
// the ray.
bool composite_partial_step(vec3 x_front, vec3 x_back, float fraction, vec3 dir, bool shading,
                            bool early, out float front, inout vec3 light_front,
                            inout vec4 acc) {
  vec3 g_back;
  float v_front = deformed_value(x_front);
  front = deformed_value_and_gradient(x_back, g_back);
  vec4 c = preintegrated_at(v_front, front);
  float f = clamp(fraction, 0.0, 1.0);
  float a = 1.0 - exp2(f * log2(max(1.0 - c.a, 1e-30)));
  c = vec4(c.rgb * (c.a > 1e-6 ? a / c.a : f), a);
  light_front.z = 0.0;
  return composite_step(c, g_back, g_shade_min_weight * f, dir, shading, early, light_front, acc);
}

// Composites one cell-gradient DVR sample (value v, gradient g in value/mm)
// front to back into acc: the table's colour and opacity, lit when shading
// (head-on when its weight in the pixel is under g_shade_min_weight). True
// when early termination ends the ray (acc.a past kOpaque).
bool composite_sample(float v, vec3 g, vec3 dir, bool shading, bool early, inout vec4 acc) {
  vec4 c = lut_at(v);
  float w = (1.0 - acc.a) * c.a;
  if (shading) {
    c.rgb = w > g_shade_min_weight ? shade(c.rgb, g, dir, 1.0)
                                : min(c.rgb * (g_shading.x + g_shading.y), vec3(1.0));
  }
  if (c.a > 0.0) {
    acc.rgb += w * c.rgb;
    acc.a += w;
    return ends_opaque(early, c.rgb, 1.0, acc);
  }
  return false;
}

uint pack_rgba(vec3 rgb) {
  uvec3 c = uvec3(clamp(rgb, 0.0, 1.0) * 255.0 + 0.5);
  return c.r | (c.g << 8) | (c.b << 16) | (255u << 24);
}

// Narrows [t_near, t_far] to the part of the ray inside every clip half
// space (crop box faces and clip planes, server/raycast/clip_region.h): the
// kept region is convex, so one interval; as ClipRayInterval on the CPU.
void clip_ray(vec3 eye, vec3 dir, inout float t_near, inout float t_far) {
  for (int i = 0; i < p.clip.x; ++i) {
    vec4 plane = p.clip_planes[i];
    float along = dot(plane.xyz, dir);
    float inside = dot(plane.xyz, eye) - plane.w;
    if (abs(along) < 1e-20) {
      if (inside < 0.0) t_far = -1.0;
    } else {
      float t = -inside / along;
      if (along > 0.0) {
        t_near = max(t_near, t);
      } else {
        t_far = min(t_far, t);
      }
    }
  }
}

// The band's row of tiles that the dispatch's row r (of `rows`) casts. A
// CPU device gives each of its `threads` threads one contiguous run of
// workgroups (server/gpu/dispatch_threads.h), here rows / threads rows of
// the dispatch; run j casts the band's rows j, j + threads, j + 2 threads,
// ..., so that every thread casts a sample of the band and none idles while
// another finishes the body's rows (rows past the last whole run stay in
// place). Rows in order on a GPU (threads 1).
uint band_row(uint r, uint rows, uint threads) {
  uint run = rows / max(threads, 1u);
  if (run == 0u || r >= run * threads) return r;
  return (r % run) * threads + r / run;
}

// The pixel of this invocation: lavapipe runs 8 consecutive invocations of
// a workgroup as one SIMD vector, and a vector costs as much as its slowest
// lane; each 8 consecutive invocations take a 4x2 block of the 8x8 tile
// (vectors 2 x 4 over it) instead of a row of 8, so that their rays stay
// closer together.
ivec2 pixel_of_invocation() {
  uint i = gl_LocalInvocationIndex;  // 0..63
  uint lane = i & 7u, vector = i >> 3;
  uvec2 local = uvec2((vector & 1u) * 4u + (lane & 3u), (vector >> 1) * 2u + (lane >> 2));
  // Band b of n takes the rows of tiles b, b + n, b + 2n, ...
  uint row = band_row(gl_WorkGroupID.y, gl_NumWorkGroups.y, uint(band.rows.z));
  uvec2 tile = uvec2(gl_WorkGroupID.x, row * uint(band.rows.y) + uint(band.rows.x));
  return ivec2(tile * 8u + local);
}

void main() {
  ivec2 px = pixel_of_invocation();
  if (px.x >= p.image.x || px.y >= p.image.y) return;
  vec2 ndc = vec2(2.0 * (float(px.x) + 0.5) / float(p.image.x) - 1.0,
                  1.0 - 2.0 * (float(px.y) + 0.5) / float(p.image.y));
  set_globals();
  vec3 eye = p.eye_mm.xyz;
  vec3 dir = normalize(p.forward.xyz + ndc.x * p.right.xyz + ndc.y * p.up.xyz);
  // No zero components: 1/dir stays finite and keeps its sign.
  vec3 safe = mix(dir, mix(vec3(1e-20), vec3(-1e-20), lessThan(dir, vec3(0.0))),
                  lessThan(abs(dir), vec3(1e-20)));
  vec3 inv_dir = 1.0 / safe;
  vec3 ta = (vec3(0.0) - eye) * inv_dir;
  vec3 tb = (extent_mm() - eye) * inv_dir;
  vec3 tmin = min(ta, tb), tmax = max(ta, tb);
  float t_near = max(max(max(tmin.x, tmin.y), tmin.z), 0.0);
  float t_far = min(min(tmax.x, tmax.y), tmax.z);
  clip_ray(eye, dir, t_near, t_far);
  uint out_index = uint(px.y) * uint(p.image.x) + uint(px.x);
  if (t_near > t_far) {
    pixels[out_index] = pack_rgba(p.background.rgb);
    return;
  }
  float step = p.eye_mm.w;
  g_shade_min_weight = kShadeMinWeight * step;
  // Jittered start (docs/RENDERING.md, "Sampling"): the samples of this ray
  // sit at t_near + (k + j) step, j from a hash of the pixel and the seed.
  float t_entry = t_near;
  if (has_flag(VPM_RAYCAST_JITTER)) {
    t_near += ray_start_jitter(uvec2(px), uint(p.image.w)) * step;
  }
  bool skipping = has_flag(VPM_RAYCAST_SKIPPING);
  uint taken = 0u;
#ifdef VPM_RAYCAST_MIP
  vec3 rgb = mip_ray(eye, dir, inv_dir, t_entry, t_near, t_far, step, skipping, taken);
#else
  int k = 0;
  bool shading = has_flag(VPM_RAYCAST_SHADING);
  bool early = has_flag(VPM_RAYCAST_EARLY_TERMINATION);
  vec4 acc = vec4(0.0);
  if (kCellGradient) {
    // Segments of the brick walk, as in the MIP loop.
    BrickWalk walk = walk_start(eye, dir, inv_dir, t_near);
    bool done = false;
    // Pre-integrated: the value at the front of the next step (that of the
    // last sample composited, k_next - 1); without partial end steps a
    // ray's first sample is a whole step of constant value.
    int k_next = 0;
    float front = 0.0;
    bool has_front = false;
    vec3 light_front = vec3(0.0);  // xy: light_factors at front; z: 1 when known
    // Partial end steps: the ray's first sample ends the step from where
    // the ray enters (the box or the clip region), the jitter's fraction of
    // a step long (none without jitter); the walk then starts at sample 1.
    bool partial_ends = kPreintegrated && has_flag(VPM_RAYCAST_PARTIAL_END_STEPS);
    if (partial_ends) {
      float t0 = min(t_near, t_far);
      done = composite_partial_step(eye + t_entry * dir, eye + t0 * dir, (t0 - t_entry) / step,
                                    dir, shading, early, front, light_front, acc);
      taken += 2u;
      has_front = true;
      k = 1;
      k_next = 1;
    }
    for (float t_end;
         !done && next_segment(walk, k, 0.0, skipping, t_near, t_far, step, t_end);
         walk_step(walk)) {
      if (kPreintegrated) {
        // After skipped samples, the step into this brick begins at the
        // sample before it; the segment ends with the first sample past the
        // brick, so that the step leaving it counts too.
        if (k != k_next) {
          has_front = k > 0;
          light_front.z = 0.0;
          front = deformed_value(eye + (t_near + float(k - 1) * step) * dir);
        }
        t_end = min(t_end + step, t_far);
      }
      vec3 x;
      segment_sample(k, t_near, step, t_end, eye, dir, x);  // next_segment: in the segment
      // Two samples per iteration, as in the MIP loop: both reads first,
      // then compositing front to back, sample by sample.
      for (;;) {
        vec3 x2;
        bool second = segment_sample(k + 1, t_near, step, t_end, eye, dir, x2);
        vec3 grad1, grad2;
        float v1 = deformed_value_and_gradient(x, grad1);
        float v2 = deformed_value_and_gradient(second ? x2 : x, grad2);
        ++taken;
        ++k;
        if (kPreintegrated ? composite_segment(has_front ? front : v1, v1, grad1, dir, shading,
                                               early, light_front, acc)
                           : composite_sample(v1, grad1, dir, shading, early, acc)) {
          done = true;
          break;
        }
        front = v1;
        has_front = true;
        if (second) {
          ++taken;
          ++k;
          if (kPreintegrated
                  ? composite_segment(front, v2, grad2, dir, shading, early, light_front, acc)
                  : composite_sample(v2, grad2, dir, shading, early, acc)) {
            done = true;
            break;
          }
          front = v2;
        }
        if (!segment_sample(k, t_near, step, t_end, eye, dir, x)) break;
      }
      k_next = k;
      if (!skipping) break;
    }
    // ... and the step from the ray's last sample to where it leaves.
    if (partial_ends && !done && t_near <= t_far) {
      float t_last = last_sample_t(t_near, t_far, step);
      float unused;
      composite_partial_step(eye + t_last * dir, eye + t_far * dir, (t_far - t_last) / step,
                             dir, shading, early, unused, light_front, acc);
      taken += 2u;
    }
  }
  int phase = 0;       // 0: the next sample; 1..6: gradient taps around x_shade
  vec3 x_shade = eye;  // the sample being shaded, its colour, its gradient so far
  vec4 c_shade = vec4(0.0);
  vec3 g = vec3(0.0);
  vec3 h = p.spacing_mm.xyz;
  for (; !kCellGradient;) {
    float t = t_near + float(k) * step;
    vec3 x = eye + t * dir;
    if (phase == 0) {
      if (skipping) skip_empty_bricks(k, t, x, 0.0, eye, dir, inv_dir, t_near, t_far, step);
      if (t > t_far) break;
      ++taken;
    }
    // Tap 1..6: +x, -x, +y, -y, +z, -z, one spacing away.
    int axis = (phase - 1) >> 1;
    vec3 along = vec3(equal(ivec3(axis), ivec3(0, 1, 2)));
    float sign = (phase & 1) == 1 ? 1.0 : -1.0;
    float v = deformed_value(phase == 0 ? x : x_shade + sign * h * along);
    vec4 c = c_shade;
    bool composite = false;
    if (phase == 0) {
      c = lut_at(v);
      if (shading && (1.0 - acc.a) * c.a > kShadeMinWeight) {
        phase = 1;
        x_shade = x;
        c_shade = c;
        g = vec3(0.0);
      } else {
        if (shading) c.rgb = min(c.rgb * (g_shading.x + g_shading.y), vec3(1.0));
        composite = c.a > 0.0;
        ++k;
      }
    } else {
      g += sign * v * along;
      if (phase == 6) {
        c.rgb = shade(c.rgb, g / (2.0 * h), dir, 1.0);
        composite = true;
        phase = 0;
        ++k;
      } else {
        ++phase;
      }
    }
    if (composite) {
      float w = (1.0 - acc.a) * c.a;
      acc.rgb += w * c.rgb;
      acc.a += w;
      if (ends_opaque(early, c.rgb, 1.0, acc)) break;
    }
  }
  vec3 rgb = acc.rgb + (1.0 - acc.a) * p.background.rgb;
#endif
  pixels[out_index] = pack_rgba(rgb);
  if (has_flag(VPM_RAYCAST_COUNT_SAMPLES)) atomicAdd(samples_taken, taken);
}

#endif

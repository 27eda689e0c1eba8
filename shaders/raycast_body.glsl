// The ray caster shared by raycast.comp (volume read from a uniform texel
// buffer, manual trilinear) and raycast_sampled.comp (volume read through a
// sampler3D with hardware trilinear filtering). One invocation per pixel.
// The CPU reference, server/render/raycast_cpu.cc, mirrors every step.
//
// Per ray: intersect the image box [0, extent_mm]; samples at
// t_k = t_near + k * step; each sample reads the deformed volume
// J(x) = I(X(x)), X from the backward map. Bricks of 8^3 cells that the
// occupancy pass marked empty (DVR: zero opacity over every value the brick
// can show; MIP: nothing above the running maximum or the window's black)
// are jumped over to the first sample grid point past them, so skipping
// never moves a sample. DVR composites front to back with opacities from
// the step-corrected table, shaded by a Blinn-Phong headlight on the
// gradient of J (central differences, 6 extra samples of J), and stops at
// accumulated opacity > 0.99.
//
// The including shader declares `float source_at(vec3 u)` (I at continuous
// index u, already clamped to [0, n - 1]) before including this file.
#ifndef VPM_RAYCAST_BODY_GLSL
#define VPM_RAYCAST_BODY_GLSL

#include "backward_map.glsl"

layout(binding = 1) uniform sampler3D u_map;
layout(std140, binding = 2) uniform Params { RaycastParams p; };
layout(std140, binding = 3) uniform Lut { vec4 entries[VPM_RENDER_LUT_ENTRIES]; } u_lut;
layout(std430, binding = 4) readonly buffer Occupancy { float occupancy[]; };
layout(std430, binding = 5) writeonly buffer Pixels { uint pixels[]; };
layout(std430, binding = 6) buffer Stats { uint samples_taken; };

const float kOpaque = 0.99;
const float kShadeMinAlpha = 1.0 / 512.0;  // lighter samples are not worth 6 reads
const float kNoValue = -3.0e38;

bool has_flag(int f) { return (p.image.z & f) != 0; }

vec3 extent_mm() { return vec3(p.dims.xyz - 1) * p.spacing_mm.xyz; }

// J(x): the source at the rest position of x (mm), clamped to the box.
float deformed_value(vec3 x) {
  vec3 rest = has_flag(VPM_RAYCAST_HAS_MAP)
                  ? rest_position(u_map, x, extent_mm(), p.map_dims.xyz)
                  : x;
  vec3 u = clamp(rest / p.spacing_mm.xyz, vec3(0.0), vec3(p.dims.xyz - 1));
  return source_at(u);
}

vec4 lut_at(float v) {
  float n = p.lut.z;
  float f = clamp((v - p.lut.x) * p.lut.y, 0.0, n - 1.0);
  int i = min(int(f), int(n) - 2);
  float t = f - float(i);
  vec4 a = u_lut.entries[i];
  vec4 b = u_lut.entries[i + 1];
  return a + (b - a) * t;
}

// Blinn-Phong with the light at the eye: the half vector is the view
// vector, so specular is |n.l|^shininess; two-sided (|n.l|).
vec3 shade(vec3 rgb, vec3 x, vec3 dir) {
  vec3 h = p.spacing_mm.xyz;
  vec3 g = vec3(deformed_value(x + vec3(h.x, 0.0, 0.0)) - deformed_value(x - vec3(h.x, 0.0, 0.0)),
                deformed_value(x + vec3(0.0, h.y, 0.0)) - deformed_value(x - vec3(0.0, h.y, 0.0)),
                deformed_value(x + vec3(0.0, 0.0, h.z)) - deformed_value(x - vec3(0.0, 0.0, h.z)));
  g = g / (2.0 * h);
  float len = length(g);
  float ndl = len > 0.0 ? abs(dot(g, dir)) / len : 1.0;
  vec3 lit = rgb * (p.shading.x + p.shading.y * ndl) + vec3(p.shading.z * pow(ndl, p.shading.w));
  return min(lit, vec3(1.0));
}

int brick_index(vec3 x) {
  ivec3 b = ivec3(floor(x / (p.spacing_mm.xyz * float(p.bricks.w))));
  b = clamp(b, ivec3(0), p.bricks.xyz - 1);
  return b.x + p.bricks.x * (b.y + p.bricks.y * b.z);
}

// Ray parameter where the ray leaves the brick holding x.
float brick_exit(vec3 x, vec3 eye, vec3 inv_dir) {
  vec3 size = p.spacing_mm.xyz * float(p.bricks.w);
  ivec3 b = clamp(ivec3(floor(x / size)), ivec3(0), p.bricks.xyz - 1);
  vec3 lo = vec3(b) * size;
  vec3 hi = min(vec3(b + 1) * size, extent_mm());
  vec3 bound = mix(lo, hi, greaterThan(inv_dir, vec3(0.0)));
  vec3 t = (bound - eye) * inv_dir;
  return min(t.x, min(t.y, t.z));
}

// First sample index past t_exit.
int next_sample(float t_exit, float t_near, float step, int k) {
  return max(k + 1, int(floor((t_exit - t_near) / step)) + 1);
}

uint pack_rgba(vec3 rgb) {
  uvec3 c = uvec3(clamp(rgb, 0.0, 1.0) * 255.0 + 0.5);
  return c.r | (c.g << 8) | (c.b << 16) | (255u << 24);
}

void raycast_pixel() {
  ivec2 px = ivec2(gl_GlobalInvocationID.xy);
  if (px.x >= p.image.x || px.y >= p.image.y) return;
  vec2 ndc = vec2(2.0 * (float(px.x) + 0.5) / float(p.image.x) - 1.0,
                  1.0 - 2.0 * (float(px.y) + 0.5) / float(p.image.y));
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
  uint out_index = uint(px.y) * uint(p.image.x) + uint(px.x);
  vec3 background = p.background.rgb;
  if (t_near > t_far) {
    pixels[out_index] = pack_rgba(background);
    return;
  }
  float step = p.eye_mm.w;
  bool mip = p.dims.w == 1;
  bool skipping = has_flag(VPM_RAYCAST_SKIPPING);
  bool shading = has_flag(VPM_RAYCAST_SHADING);
  bool early = has_flag(VPM_RAYCAST_EARLY_TERMINATION);
  float ray_max = kNoValue;
  vec4 acc = vec4(0.0);
  uint taken = 0u;
  int k = 0;
  for (;;) {
    float t = t_near + float(k) * step;
    if (t > t_far) break;
    vec3 x = eye + t * dir;
    if (skipping) {
      float occ = occupancy[brick_index(x)];
      bool empty = mip ? occ <= max(ray_max, p.window.x) : occ <= 0.0;
      if (empty) {
        k = next_sample(brick_exit(x, eye, inv_dir), t_near, step, k);
        continue;
      }
    }
    ++taken;
    float v = deformed_value(x);
    if (mip) {
      ray_max = max(ray_max, v);
    } else {
      vec4 c = lut_at(v);
      if (c.a > 0.0) {
        vec3 rgb = (shading && c.a > kShadeMinAlpha) ? shade(c.rgb, x, dir) : c.rgb;
        float w = (1.0 - acc.a) * c.a;
        acc.rgb += w * rgb;
        acc.a += w;
        if (early && acc.a > kOpaque) break;
      }
    }
    ++k;
  }
  vec3 rgb = mip ? vec3(clamp((ray_max - p.window.x) * p.window.y, 0.0, 1.0))
                 : acc.rgb + (1.0 - acc.a) * background;
  pixels[out_index] = pack_rgba(rgb);
  if (has_flag(VPM_RAYCAST_COUNT_SAMPLES)) atomicAdd(samples_taken, taken);
}

#endif

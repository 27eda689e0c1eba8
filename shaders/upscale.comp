#version 450
#extension GL_GOOGLE_include_directive : require
// Resize of a packed RGBA8 image (interactive frames ray cast at a fraction
// of the size, shown at full): bilinear, or Catmull-Rom bicubic (4 x 4
// texels, weights of the cubic through the samples; sharper edges, may
// overshoot: the result is clamped to [0, 1]). Pixel centres map as
// src = (dst + 0.5) * src_size / dst_size - 0.5, clamped to the image;
// texels past the border repeat the edge. UpscaleCpu mirrors it.
#include "shader_interface.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Source { uint source[]; };
layout(std430, binding = 1) writeonly buffer Target { uint target[]; };
layout(push_constant) uniform Push { UpscalePush pc; };

vec4 texel(ivec2 q) { return unpackUnorm4x8(source[q.y * pc.size.x + q.x]); }

// Catmull-Rom weights of the texels at -1, 0, 1, 2 for a fraction t.
vec4 catmull_rom(float t) {
  float t2 = t * t;
  float t3 = t2 * t;
  return vec4(-0.5 * t3 + t2 - 0.5 * t, 1.5 * t3 - 2.5 * t2 + 1.0,
              -1.5 * t3 + 2.0 * t2 + 0.5 * t, 0.5 * t3 - 0.5 * t2);
}

vec4 bilinear(vec2 s) {
  ivec2 i0 = ivec2(floor(s));
  ivec2 i1 = min(i0 + 1, pc.size.xy - 1);
  vec2 f = s - vec2(i0);
  vec4 top = texel(i0) + (texel(ivec2(i1.x, i0.y)) - texel(i0)) * f.x;
  vec4 bottom = texel(ivec2(i0.x, i1.y)) + (texel(i1) - texel(ivec2(i0.x, i1.y))) * f.x;
  return top + (bottom - top) * f.y;
}

vec4 bicubic(vec2 s) {
  ivec2 i0 = ivec2(floor(s));
  vec2 f = s - vec2(i0);
  vec4 wx = catmull_rom(f.x);
  vec4 wy = catmull_rom(f.y);
  ivec4 xs = clamp(i0.x + ivec4(-1, 0, 1, 2), 0, pc.size.x - 1);
  vec4 c = vec4(0.0);
  for (int r = 0; r < 4; ++r) {
    int y = clamp(i0.y - 1 + r, 0, pc.size.y - 1);
    vec4 row = texel(ivec2(xs.x, y)) * wx.x + texel(ivec2(xs.y, y)) * wx.y +
               texel(ivec2(xs.z, y)) * wx.z + texel(ivec2(xs.w, y)) * wx.w;
    c += row * wy[r];
  }
  return c;
}

// Each invocation writes kPixelsPerInvocation consecutive pixels of a row:
// on lavapipe the fixed cost per invocation (index arithmetic, bounds, lane
// masks) is much of this small kernel's cost.
const int kPixelsPerInvocation = 4;

void main() {
  ivec2 d0 = ivec2(gl_GlobalInvocationID.xy) * ivec2(kPixelsPerInvocation, 1);
  if (d0.x >= pc.size.z || d0.y >= pc.size.w) return;
  vec2 scale = vec2(pc.size.xy) / vec2(pc.size.zw);
  for (int j = 0; j < kPixelsPerInvocation; ++j) {
    ivec2 d = d0 + ivec2(j, 0);
    if (d.x >= pc.size.z) break;
    vec2 s = clamp((vec2(d) + 0.5) * scale - 0.5, vec2(0.0), vec2(pc.size.xy - 1));
    vec4 c = pc.mode.x == kUpscaleCatmullRom ? bicubic(s) : bilinear(s);
    uvec4 q = uvec4(clamp(c, 0.0, 1.0) * 255.0 + 0.5);
    target[d.y * pc.size.z + d.x] = q.r | (q.g << 8) | (q.b << 16) | (q.a << 24);
  }
}

#version 450
#extension GL_GOOGLE_include_directive : require
// Bilinear resize of a packed RGBA8 image (interactive frames: ray cast at
// half resolution, shown at full). Pixel centres map as
// src = (dst + 0.5) * src_size / dst_size - 0.5, clamped to the image.
#include "shader_interface.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(std430, binding = 0) readonly buffer Source { uint source[]; };
layout(std430, binding = 1) writeonly buffer Target { uint target[]; };
layout(push_constant) uniform Push { UpscalePush pc; };

vec4 texel(ivec2 q) { return unpackUnorm4x8(source[q.y * pc.size.x + q.x]); }

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
    ivec2 i0 = ivec2(floor(s));
    ivec2 i1 = min(i0 + 1, pc.size.xy - 1);
    vec2 f = s - vec2(i0);
    vec4 top = texel(i0) + (texel(ivec2(i1.x, i0.y)) - texel(i0)) * f.x;
    vec4 bottom = texel(ivec2(i0.x, i1.y)) + (texel(i1) - texel(ivec2(i0.x, i1.y))) * f.x;
    vec4 c = top + (bottom - top) * f.y;
    uvec4 q = uvec4(clamp(c, 0.0, 1.0) * 255.0 + 0.5);
    target[d.y * pc.size.z + d.x] = q.r | (q.g << 8) | (q.b << 16) | (q.a << 24);
  }
}

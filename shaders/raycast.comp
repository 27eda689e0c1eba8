#version 450
#extension GL_GOOGLE_include_directive : require
// Ray casting, volume read from a uniform texel buffer (R32F, x fastest)
// with manual trilinear interpolation: the faster of the two on lavapipe
// (docs/RENDERING.md). 8x8 pixels per workgroup. Body: raycast_body.glsl.
#include "shader_interface.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform samplerBuffer u_volume;

// I at continuous index u in [0, n - 1]: lerps in the order x, y, z, each
// a + (b - a) * f, as the CPU reference.
float source_at(vec3 u);

#include "raycast_body.glsl"

float source_at(vec3 u) {
  ivec3 n = p.dims.xyz;
  ivec3 i0 = min(ivec3(floor(u)), n - 2);
  vec3 f = u - vec3(i0);
  int sx = 1, sy = n.x, sz = n.x * n.y;
  int base = i0.x + sy * i0.y + sz * i0.z;
  float c000 = texelFetch(u_volume, base).r;
  float c100 = texelFetch(u_volume, base + sx).r;
  float c010 = texelFetch(u_volume, base + sy).r;
  float c110 = texelFetch(u_volume, base + sy + sx).r;
  float c001 = texelFetch(u_volume, base + sz).r;
  float c101 = texelFetch(u_volume, base + sz + sx).r;
  float c011 = texelFetch(u_volume, base + sz + sy).r;
  float c111 = texelFetch(u_volume, base + sz + sy + sx).r;
  float c00 = c000 + (c100 - c000) * f.x;
  float c10 = c010 + (c110 - c010) * f.x;
  float c01 = c001 + (c101 - c001) * f.x;
  float c11 = c011 + (c111 - c011) * f.x;
  float c0 = c00 + (c10 - c00) * f.y;
  float c1 = c01 + (c11 - c01) * f.y;
  return c0 + (c1 - c0) * f.z;
}

void main() { raycast_pixel(); }

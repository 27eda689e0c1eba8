#version 450
#extension GL_GOOGLE_include_directive : require
// Ray casting, volume read through a sampler3D (R32F 3D image, linear
// filtering, clamp to edge); otherwise raycast.comp. Hardware filtering
// weights have limited sub-texel precision (8 bits on lavapipe), so this
// variant differs from the CPU reference by a little more.
#include "shader_interface.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_volume;

float source_at(vec3 u);

#include "raycast_body.glsl"

float source_at(vec3 u) { return textureLod(u_volume, (u + 0.5) / vec3(p.dims.xyz), 0.0).r; }

void main() { raycast_pixel(); }

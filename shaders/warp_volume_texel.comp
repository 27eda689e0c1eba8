#version 450
#extension GL_GOOGLE_include_directive : require
// J(x) = I(X(x)) per voxel, the source read through its uniform texel buffer
// with a manual trilinear interpolation, the same arithmetic as
// SampleTrilinear (server/volume/sample_trilinear.h). One invocation per
// voxel, 64 along x.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(binding = 1) uniform isamplerBuffer u_volume;
layout(std430, binding = 2) writeonly buffer Out { float warped[]; };
layout(push_constant) uniform Push { WarpVolumePush pc; };

#include "source_texel_trilinear.glsl"

#include "warp_volume.glsl"

void main() { warp_voxel(); }

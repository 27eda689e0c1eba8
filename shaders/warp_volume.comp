#version 450
#extension GL_GOOGLE_include_directive : require
// J(x) = I(X(x)) per voxel, the source read through its 3D image with the
// hardware trilinear filter (clamp to edge = the clamped indexing of
// section 0). One invocation per voxel, 64 along x.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform sampler3D u_map;
layout(binding = 1) uniform sampler3D u_source;
layout(std430, binding = 2) writeonly buffer Out { float warped[]; };
layout(push_constant) uniform Push { WarpVolumePush pc; };

#include "voxel_encoding.glsl"

float sample_source(vec3 index) {
  return decode_image_voxel(textureLod(u_source, (index + 0.5) / vec3(pc.dims.xyz), 0.0).r);
}

#include "warp_volume.glsl"

void main() { warp_voxel(); }

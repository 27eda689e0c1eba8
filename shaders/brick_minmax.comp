#version 450
#extension GL_GOOGLE_include_directive : require
// Min and max of the source volume over each brick of wx x wy x wz cells
// (w = pc.brick_voxels.xyz, about 6 mm for still frames and 12 mm for
// interactive ones, RenderBrickVoxels): brick b spans voxels
// [w b, min(w b + w, n - 1)] per axis, boundary layers shared,
// so every trilinear sample at an index inside the brick reads only voxels
// it covers. One invocation per brick; built once per volume.
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform isamplerBuffer u_volume;
layout(std430, binding = 1) writeonly buffer MinMax { vec2 minmax[]; };
layout(push_constant) uniform Push { BrickMinMaxPush pc; };

#include "volume_access.glsl"

void main() {
  ivec3 nb = pc.bricks.xyz;
  int index = int(gl_GlobalInvocationID.x);
  if (index >= nb.x * nb.y * nb.z) return;
  ivec3 b = ivec3(index % nb.x, (index / nb.x) % nb.y, index / (nb.x * nb.y));
  ivec3 n = pc.dims.xyz;
  ivec3 w = pc.brick_voxels.xyz;
  ivec3 lo = b * w;
  ivec3 hi = min(lo + w, n - 1);
  float vmin = 3.0e38, vmax = -3.0e38;
  for (int z = lo.z; z <= hi.z; ++z) {
    for (int y = lo.y; y <= hi.y; ++y) {
      int row = n.x * (y + n.y * z);
      for (int x = lo.x; x <= hi.x; ++x) {
        float v = voxel_linear(row + x);
        vmin = min(vmin, v);
        vmax = max(vmax, v);
      }
    }
  }
  minmax[index] = vec2(vmin, vmax);
}

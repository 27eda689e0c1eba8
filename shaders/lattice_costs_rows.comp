#version 450
#extension GL_GOOGLE_include_directive : require
// Step 1 (docs/ALGORITHM.md section 1), pass 1 of 2: partial cell footprints per
// voxel row. Invocation i walks the x range of lattice cell cx along one
// voxel row (y, z) and writes partials[i] = (sum of TF, max |grad I|^2) over
// that row segment, with i = (row - first row of the chunk) * Gx + cx and
// row = y + ny * (z - z0). The x neighbours slide along in registers, so
// each voxel costs five fetches (value, x+1, y-1, y+1, z-1, z+1 minus the
// reused x-1). No shared memory and no barriers: on lavapipe a workgroup
// barrier switches every invocation's coroutine, which made the earlier
// one-workgroup-per-cell kernel with a shared-memory slice ring 5x slower
// than the CPU reference (docs/MESH.md).
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform isamplerBuffer u_volume;
layout(std140, binding = 1) uniform TransferFunctionBlock {
  vec4 points[VPM_MAX_TF_POINTS];
  ivec4 count;
} u_tf;
layout(std430, binding = 2) writeonly buffer Partials { vec2 partials[]; };
layout(push_constant) uniform Push { LatticeCostsPush pc; };

#include "lattice_cells.glsl"
#include "transfer_function.glsl"
#include "volume_access.glsl"

void main() {
  // Dispatches wider than the 65535-group limit fold into y.
  uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u +
           gl_LocalInvocationID.x;
  ivec3 dims = pc.dims.xyz;
  uint gx = uint(pc.grid.x);
  int z0 = pc.chunk.x;
  uint rows = uint(dims.y) * uint(pc.chunk.y - z0);
  if (i >= gx * rows) return;
  int cx = int(i % gx);
  int row = int(i / gx);
  int y = row % dims.y;
  int z = z0 + row / dims.y;
  ivec2 rx = cell_range(cx, dims.x, int(gx));
  // Offsets (voxels) of the rows this segment and its y/z neighbours lie on,
  // clamped at the volume's faces (docs/ALGORITHM.md section 0).
  int here = dims.x * (y + dims.y * z);
  int y_lo = dims.x * (max(y - 1, 0) + dims.y * z);
  int y_hi = dims.x * (min(y + 1, dims.y - 1) + dims.y * z);
  int z_lo = dims.x * (y + dims.y * max(z - 1, 0));
  int z_hi = dims.x * (y + dims.y * min(z + 1, dims.z - 1));
  vec3 inv2s = pc.inv_two_spacing.xyz;

  float left = voxel_linear(here + max(rx.x - 1, 0));
  float value = voxel_linear(here + rx.x);
  float sum = 0.0;
  float max_g2 = 0.0;  // max of |grad|^2; the cell pass takes one sqrt
  for (int x = rx.x; x < rx.y; ++x) {
    float right = voxel_linear(here + min(x + 1, dims.x - 1));
    float gx_ = (right - left) * inv2s.x;
    float gy = (voxel_linear(y_hi + x) - voxel_linear(y_lo + x)) * inv2s.y;
    float gz = (voxel_linear(z_hi + x) - voxel_linear(z_lo + x)) * inv2s.z;
    sum += transfer_cost(value);
    max_g2 = max(max_g2, gx_ * gx_ + gy * gy + gz * gz);
    left = value;
    value = right;
  }
  partials[i] = vec2(sum, max_g2);
}

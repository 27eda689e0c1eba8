#version 450
#extension GL_GOOGLE_include_directive : require
// Step 1 (ALGORITHM.md section 1) for every lattice vertex, both footprints:
// out[id] = (mean TF over the cell, max |grad I| over the cell,
//            TF at voxel(v), |grad I| at voxel(v)).
// One workgroup per vertex (cell); its 8x8 invocations stride over the
// cell's voxels (x and y, every z) and reduce in shared memory (no float
// atomics). No integer division per voxel: lavapipe has no vector divide.
#include "shader_interface.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(binding = 0) uniform samplerBuffer u_volume;
layout(std140, binding = 1) uniform TransferFunctionBlock {
  vec4 points[VPM_MAX_TF_POINTS];
  ivec4 count;
} u_tf;
layout(std430, binding = 2) writeonly buffer Out { vec4 costs[]; };
layout(push_constant) uniform Push { LatticeCostsPush pc; };

#include "transfer_function.glsl"
#include "volume_access.glsl"

shared float s_sum[64];
shared float s_max[64];

// Half-open voxel range of cell `c` along an axis with n voxels and g cells:
// [floor(c*n/g), floor((c+1)*n/g)).
ivec2 cell_range(int c, int n, int g) { return ivec2((c * n) / g, ((c + 1) * n) / g); }

void main() {
  ivec3 cell = ivec3(gl_WorkGroupID);
  ivec3 dims = pc.dims.xyz;
  ivec3 grid = pc.grid.xyz;
  ivec2 rx = cell_range(cell.x, dims.x, grid.x);
  ivec2 ry = cell_range(cell.y, dims.y, grid.y);
  ivec2 rz = cell_range(cell.z, dims.z, grid.z);
  int count = (rx.y - rx.x) * (ry.y - ry.x) * (rz.y - rz.x);

  float sum = 0.0;
  // The max of |grad|^2, square-rooted once: sqrt is monotonic and correctly
  // rounded, so this equals the max of |grad|.
  float max_g2 = 0.0;
  for (int z = rz.x; z < rz.y; ++z) {
    for (int y = ry.x + int(gl_LocalInvocationID.y); y < ry.y; y += 8) {
      for (int x = rx.x + int(gl_LocalInvocationID.x); x < rx.y; x += 8) {
        ivec3 p = ivec3(x, y, z);
        sum += transfer_cost(voxel_at(p, dims));
        max_g2 = max(max_g2, gradient_squared_at(p, dims, pc.inv_two_spacing.xyz));
      }
    }
  }
  uint lid = gl_LocalInvocationIndex;
  s_sum[lid] = sum;
  s_max[lid] = max_g2;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1u) {
    if (lid < stride) {
      s_sum[lid] += s_sum[lid + stride];
      s_max[lid] = max(s_max[lid], s_max[lid + stride]);
    }
    barrier();
  }
  if (lid == 0u) {
    // voxel(v) = floor((2c+1) n / (2g)), the nearest voxel to the cell centre.
    ivec3 v = min((2 * cell + 1) * dims / (2 * grid), dims - 1);
    float point_ci = transfer_cost(voxel_at(v, dims));
    float point_g = gradient_magnitude_at(v, dims, pc.inv_two_spacing.xyz);
    uint id = uint(cell.x) + uint(grid.x) * (uint(cell.y) + uint(grid.y) * uint(cell.z));
    costs[id] = vec4(s_sum[0] / float(count), sqrt(s_max[0]), point_ci, point_g);
  }
}

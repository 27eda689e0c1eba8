#version 450
#extension GL_GOOGLE_include_directive : require
// Step 1 (ALGORITHM.md section 1) for every lattice vertex, both footprints:
// out[id] = (mean TF over the cell, max |grad I| over the cell,
//            TF at voxel(v), |grad I| at voxel(v)).
//
// One workgroup of 8x8 invocations per vertex (cell). The cell is walked in
// 8x8 tiles; for each tile the workgroup streams z slices of the tile plus a
// one-voxel halo (10x10) through a ring of three slices in shared memory, so
// each voxel is fetched about twice instead of seven times (its value and
// six neighbours). Sums and maxima reduce in shared memory: no float atomics.
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

shared float s_slice[3][10][10];  // ring of z slices: tile plus halo, clamped reads
shared float s_sum[64];
shared float s_max[64];

// Half-open voxel range of cell `c` along an axis with n voxels and g cells:
// [floor(c*n/g), floor((c+1)*n/g)).
ivec2 cell_range(int c, int n, int g) { return ivec2((c * n) / g, ((c + 1) * n) / g); }

// Loads slice z (clamped) of the 10x10 region whose (0,0) is voxel origin.xy.
void load_slice(int slot, ivec2 origin, int z, ivec3 dims) {
  int zc = clamp(z, 0, dims.z - 1);
  for (uint t = gl_LocalInvocationIndex; t < 100u; t += 64u) {
    int i = int(t % 10u), j = int(t / 10u);
    ivec3 p = ivec3(clamp(origin.x + i, 0, dims.x - 1), clamp(origin.y + j, 0, dims.y - 1), zc);
    s_slice[slot][j][i] = voxel_at(p, dims);
  }
}

void main() {
  ivec3 cell = ivec3(gl_WorkGroupID);
  ivec3 dims = pc.dims.xyz;
  ivec3 grid = pc.grid.xyz;
  vec3 inv2s = pc.inv_two_spacing.xyz;
  ivec2 rx = cell_range(cell.x, dims.x, grid.x);
  ivec2 ry = cell_range(cell.y, dims.y, grid.y);
  ivec2 rz = cell_range(cell.z, dims.z, grid.z);
  int count = (rx.y - rx.x) * (ry.y - ry.x) * (rz.y - rz.x);
  ivec2 lid = ivec2(gl_LocalInvocationID.xy);

  float sum = 0.0;
  // The max of |grad|^2, square-rooted once: sqrt is monotonic and correctly
  // rounded, so this equals the max of |grad|.
  float max_g2 = 0.0;
  for (int ty = ry.x; ty < ry.y; ty += 8) {
    for (int tx = rx.x; tx < rx.y; tx += 8) {
      ivec2 origin = ivec2(tx - 1, ty - 1);
      bool mine = tx + lid.x < rx.y && ty + lid.y < ry.y;
      load_slice(0, origin, rz.x - 1, dims);
      load_slice(1, origin, rz.x, dims);
      for (int z = rz.x; z < rz.y; ++z) {
        int below = (z - rz.x) % 3, here = (z - rz.x + 1) % 3, above = (z - rz.x + 2) % 3;
        load_slice(above, origin, z + 1, dims);
        barrier();
        if (mine) {
          int i = lid.x + 1, j = lid.y + 1;
          float value = s_slice[here][j][i];
          float gx = (s_slice[here][j][i + 1] - s_slice[here][j][i - 1]) * inv2s.x;
          float gy = (s_slice[here][j + 1][i] - s_slice[here][j - 1][i]) * inv2s.y;
          float gz = (s_slice[above][j][i] - s_slice[below][j][i]) * inv2s.z;
          sum += transfer_cost(value);
          max_g2 = max(max_g2, gx * gx + gy * gy + gz * gz);
        }
        barrier();  // the next load overwrites `below`
      }
    }
  }
  uint l = gl_LocalInvocationIndex;
  s_sum[l] = sum;
  s_max[l] = max_g2;
  barrier();
  for (uint stride = 32u; stride > 0u; stride >>= 1u) {
    if (l < stride) {
      s_sum[l] += s_sum[l + stride];
      s_max[l] = max(s_max[l], s_max[l + stride]);
    }
    barrier();
  }
  if (l == 0u) {
    // voxel(v) = floor((2c+1) n / (2g)), the nearest voxel to the cell centre.
    ivec3 v = min((2 * cell + 1) * dims / (2 * grid), dims - 1);
    float point_ci = transfer_cost(voxel_at(v, dims));
    float point_g = gradient_magnitude_at(v, dims, inv2s);
    uint id = uint(cell.x) + uint(grid.x) * (uint(cell.y) + uint(grid.y) * uint(cell.z));
    costs[id] = vec4(s_sum[0] / float(count), sqrt(s_max[0]), point_ci, point_g);
  }
}

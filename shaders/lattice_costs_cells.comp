#version 450
#extension GL_GOOGLE_include_directive : require
// Step 1 (docs/ALGORITHM.md section 1), pass 2 of 2: one invocation per lattice
// vertex (cell) of the chunk's cell layers [cz0, cz1) reduces the row
// partials of pass 1 over its (y, z) rows in a fixed order and writes
// costs[id] = (mean TF over the cell, max |grad I| over the cell,
//              TF at voxel(v), |grad I| at voxel(v)).
#include "shader_interface.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;
layout(binding = 0) uniform isamplerBuffer u_volume;
layout(std140, binding = 1) uniform TransferFunctionBlock {
  vec4 points[VPM_MAX_TF_POINTS];
  ivec4 count;
} u_tf;
layout(std430, binding = 2) readonly buffer Partials { vec2 partials[]; };
layout(std430, binding = 3) writeonly buffer Out { vec4 costs[]; };
layout(push_constant) uniform Push { LatticeCostsPush pc; };

#include "lattice_cells.glsl"
#include "transfer_function.glsl"
#include "volume_access.glsl"

void main() {
  uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * 64u +
           gl_LocalInvocationID.x;
  ivec3 dims = pc.dims.xyz;
  ivec3 grid = pc.grid.xyz;
  int z0 = pc.chunk.x, cz0 = pc.chunk.z;
  uint layer = uint(grid.x) * uint(grid.y);
  if (i >= layer * uint(pc.chunk.w - cz0)) return;
  ivec3 cell = ivec3(int(i % uint(grid.x)), int((i / uint(grid.x)) % uint(grid.y)),
                     cz0 + int(i / layer));
  ivec2 rx = cell_range(cell.x, dims.x, grid.x);
  ivec2 ry = cell_range(cell.y, dims.y, grid.y);
  ivec2 rz = cell_range(cell.z, dims.z, grid.z);
  float sum = 0.0;
  float max_g2 = 0.0;
  for (int z = rz.x; z < rz.y; ++z) {
    for (int y = ry.x; y < ry.y; ++y) {
      vec2 p = partials[(uint(y) + uint(dims.y) * uint(z - z0)) * uint(grid.x) + uint(cell.x)];
      sum += p.x;
      max_g2 = max(max_g2, p.y);
    }
  }
  int count = (rx.y - rx.x) * (ry.y - ry.x) * (rz.y - rz.x);
  // voxel(v) = floor((2c+1) n / (2g)), the nearest voxel to the cell centre.
  ivec3 v = min((2 * cell + 1) * dims / (2 * grid), dims - 1);
  uint id = uint(cell.x) + uint(grid.x) * (uint(cell.y) + uint(grid.y) * uint(cell.z));
  // sqrt is monotonic and correctly rounded: sqrt(max |grad|^2) = max |grad|.
  costs[id] = vec4(sum / float(count), sqrt(max_g2), transfer_cost(voxel_at(v, dims)),
                   gradient_magnitude_at(v, dims, pc.inv_two_spacing.xyz));
}

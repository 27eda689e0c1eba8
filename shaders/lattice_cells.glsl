// The lattice cells of docs/ALGORITHM.md section 1 (the `cell` footprint): along
// an axis of n voxels and g lattice vertices, cell c covers the half-open
// voxel range [floor(c n / g), floor((c + 1) n / g)); the cells partition
// the volume.
#ifndef VPM_LATTICE_CELLS_GLSL
#define VPM_LATTICE_CELLS_GLSL

ivec2 cell_range(int c, int n, int g) { return ivec2((c * n) / g, ((c + 1) * n) / g); }

#endif

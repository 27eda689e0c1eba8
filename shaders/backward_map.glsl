// The backward map of docs/ALGORITHM.md section 7, as the ray caster and the warp
// read it (docs/WARP.md).
//
// The map is an RGBA32F 3D image of M = (mx, my, mz) grid points covering
// the image box corner to corner: point (a, b, c) sits at physical position
// p = (a, b, c) * extent_mm / (M - 1), extent_mm = (n - 1) * spacing. Its
// texel holds (X(p) - p, inside): X(p) is the rest position of p found
// through the deformed tet containing p (mm); inside is 1 where p lies in a
// deformed tet, else 0 with displacement 0 (identity outside the mesh).
// Bound with its linear, clamp-to-edge sampler, so between grid points the
// displacement is trilinear and beyond the box it is that of the nearest
// face.
#ifndef VPM_BACKWARD_MAP_GLSL
#define VPM_BACKWARD_MAP_GLSL

// (X(p) - p in mm, inside fraction) at physical position p_mm (mm).
// map_dims: M as floats; extent_mm: (n - 1) * spacing, every component > 0.
vec4 backward_map_sample(sampler3D map, vec3 p_mm, vec3 extent_mm, vec3 map_dims) {
  vec3 uvw = (p_mm / extent_mm * (map_dims - 1.0) + 0.5) / map_dims;
  return textureLod(map, uvw, 0.0);
}

// X(p): the rest (source) position of the deformed-space point p_mm, in mm.
vec3 rest_position(sampler3D map, vec3 p_mm, vec3 extent_mm, vec3 map_dims) {
  return p_mm + backward_map_sample(map, p_mm, extent_mm, map_dims).xyz;
}

#endif

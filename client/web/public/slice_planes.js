// Where the three named slice planes go to pass through a point. The named
// planes' normals are the world axes (server/raycast/slice_grid.cc: axial
// +z, coronal +y, sagittal +x, LPS), so a plane's position (SliceSpec.at_mm,
// mm along its normal) through point p is p's coordinate on that axis.

// pointMm: {x, y, z} world LPS, mm. Returns {axial, coronal, sagittal}: at_mm.
export function planesThrough(pointMm) {
  return { axial: pointMm.z, coronal: pointMm.y, sagittal: pointMm.x };
}

// The point the grabbed tissue is pulled to: the grab's point
// (Frame.grab_point_mm, [x, y, z]) plus the drag offset the page sent last
// ({x, y, z} or null), world LPS mm; {x, y, z}.
export function grabTargetMm(grabPointMm, dragOffsetMm) {
  const o = dragOffsetMm ?? { x: 0, y: 0, z: 0 };
  return { x: grabPointMm[0] + o.x, y: grabPointMm[1] + o.y, z: grabPointMm[2] + o.z };
}

// `at` clamped into a slice geometry's range (min_offset_mm, max_offset_mm:
// where the plane still meets the volume); unclamped without a geometry.
export function clampToSlice(at, geometry) {
  if (!geometry) return at;
  return Math.min(geometry.max_offset_mm, Math.max(geometry.min_offset_mm, at));
}

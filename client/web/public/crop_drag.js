// Dragging the crop box's faces in the 3D view (the Crop tool), as vpm-view
// does (client/view/crop_box_drag.h): the face the pixel's ray enters the
// box through, and how far a drag moves it along its normal.
//
// The box is world (LPS) mm, [lo, hi] per axis, as RenderSettings.crop;
// the camera (camera.js) lives in physical voxel space (index * spacing,
// mm); `volume` (VolumeInfo: origin_lps_mm, direction) maps between them.
// Frame pixels: row 0 at the top, of the frame's full size.

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

function directionColumns(volume) {
  const d = volume.direction?.length === 9 ? volume.direction : [1, 0, 0, 0, 1, 0, 0, 0, 1];
  return [d.slice(0, 3), d.slice(3, 6), d.slice(6, 9)];
}

// World position of physical point p, and world direction of physical v.
export function physicalToWorld(volume, p) {
  const c = directionColumns(volume);
  const o = volume.origin_lps_mm ?? { x: 0, y: 0, z: 0 };
  return [o.x, o.y, o.z].map((oa, r) => oa + c[0][r] * p[0] + c[1][r] * p[1] + c[2][r] * p[2]);
}
function directionToWorld(volume, v) {
  const c = directionColumns(volume);
  return [0, 1, 2].map((r) => c[0][r] * v[0] + c[1][r] * v[1] + c[2][r] * v[2]);
}
// Physical direction of world direction w: D^T w.
export function directionToPhysical(volume, w) {
  return directionColumns(volume).map((c) => dot(c, w));
}

// Physical position of world point w: D^T (w - origin).
export function worldToPhysical(volume, w) {
  const o = volume.origin_lps_mm ?? { x: 0, y: 0, z: 0 };
  return directionToPhysical(volume, [w[0] - o.x, w[1] - o.y, w[2] - o.z]);
}

// The crop box's 12 edges as frame segments [x0, y0, x1, y1] (pixels, row 0
// at the top), for drawing its outline over the frame; an edge with an end
// behind the eye is left out.
export function boxOutlineSegments(camera, volume, box, width, height) {
  const corner = (c) => camera.projectToPixel(
    worldToPhysical(volume, [0, 1, 2].map((a) => (c >> a) & 1 ? box.hi[a] : box.lo[a])),
    width, height);
  const pixels = Array.from({ length: 8 }, (_, c) => corner(c));
  const segments = [];
  for (let c = 0; c < 8; ++c) {
    for (let a = 0; a < 3; ++a) {
      const d = c | (1 << a);
      if (d === c || !pixels[c] || !pixels[d]) continue;
      segments.push([...pixels[c], ...pixels[d]]);
    }
  }
  return segments;
}

// {axis, high} of the face through which the ray of pixel (px, py) enters
// `box` (leaves it, when the eye is inside), or null when it misses.
export function pickBoxFace(camera, volume, box, px, py, width, height) {
  const eye = physicalToWorld(volume, camera.eye());
  const dir = directionToWorld(volume, camera.rayDirection(px, py, width, height));
  let tIn = -Infinity, tOut = Infinity, inFace = null, outFace = null;
  for (let a = 0; a < 3; ++a) {
    if (Math.abs(dir[a]) < 1e-12) {
      if (eye[a] < box.lo[a] || eye[a] > box.hi[a]) return null;
      continue;
    }
    const tLo = (box.lo[a] - eye[a]) / dir[a], tHi = (box.hi[a] - eye[a]) / dir[a];
    // Moving along +a the ray enters at lo and leaves at hi.
    if (Math.min(tLo, tHi) > tIn) [tIn, inFace] = [Math.min(tLo, tHi), { axis: a, high: dir[a] < 0 }];
    if (Math.max(tLo, tHi) < tOut) [tOut, outFace] = [Math.max(tLo, tHi), { axis: a, high: dir[a] > 0 }];
  }
  if (!(tIn <= tOut) || tOut < 0) return null;
  return tIn >= 0 ? inFace : outFace;
}

// How far (mm along +axis) a screen motion of (dx, dy) frame pixels moves
// `face`: the motion along the face normal's image on screen, at the
// orbit centre's scale; a normal nearly along the view (its image under a
// fifth of its length): dragging up moves the face away from the viewer.
export function faceDragMm(camera, volume, face, dx, dy, width, height) {
  const w = [0, 0, 0];
  w[face.axis] = 1;
  const n = directionToPhysical(volume, w);
  const mm = camera.mmPerPixel(width, height);
  const s = [dot(n, camera.right()), -dot(n, camera.up())];
  const s2 = s[0] * s[0] + s[1] * s[1];
  if (s2 < 0.04) return -dy * mm * (dot(n, camera.forward()) >= 0 ? 1 : -1);
  return (mm * (dx * s[0] + dy * s[1])) / s2;
}

// `start` with `face` moved by deltaMm along +axis, inside `limits` and at
// least gapMm from the opposite face.
export function moveBoxFace(start, face, deltaMm, limits, gapMm = 1) {
  const box = { lo: [...start.lo], hi: [...start.hi] };
  const a = face.axis;
  const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
  if (face.high) {
    box.hi[a] = clamp(start.hi[a] + deltaMm, Math.min(start.lo[a] + gapMm, limits.hi[a]), limits.hi[a]);
  } else {
    box.lo[a] = clamp(start.lo[a] + deltaMm, limits.lo[a], Math.max(start.hi[a] - gapMm, limits.lo[a]));
  }
  return box;
}

// The Crop tool's maths (client/web/public/crop_drag.js): the face a pixel
// picks against a brute-force nearest hit, a face following the pointer
// along its image on screen, the head-on rule and the limits.
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const pub = (f) => pathToFileURL(path.join(here, '../../client/web/public', f)).href;
const { OrbitCamera } = await import(pub('camera.js'));
const { worldBox } = await import(pub('cut_controls.js'));
const { boxOutlineSegments, directionToPhysical, faceDragMm, moveBoxFace, physicalToWorld,
        pickBoxFace, worldToPhysical } = await import(pub('crop_drag.js'));

const W = 200, H = 160;
// Rotated 90 degrees about world z and mirrored in z, away from the origin.
const volume = { dims: [64, 48, 40], spacing_mm: { x: 1.5, y: 2, z: 2.5 },
                 origin_lps_mm: { x: -40, y: 25, z: 100 },
                 direction: [0, 1, 0, -1, 0, 0, 0, 0, -1] };
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
// Image position (pixels) of physical point p (Camera::Project).
function project(c, p) {
  const v = sub(p, c.eye());
  const depth = dot(v, c.forward());
  const tanHalf = Math.tan((15 * Math.PI) / 180);
  const shorter = Math.min(W, H);
  const nx = dot(v, c.right()) / (depth * tanHalf * W / shorter);
  const ny = dot(v, c.up()) / (depth * tanHalf * H / shorter);
  return [((nx + 1) * W) / 2, ((1 - ny) * H) / 2];
}

function bruteForce(c, box, px, py) {
  const eye = physicalToWorld(volume, c.eye());
  const d = c.rayDirection(px, py, W, H);
  const o = physicalToWorld(volume, [0, 0, 0]);
  const dir = sub(physicalToWorld(volume, d), o);
  let best = Infinity, face = null;
  for (let a = 0; a < 3; ++a) {
    for (const high of [false, true]) {
      if (dir[a] === 0) continue;
      const t = ((high ? box.hi[a] : box.lo[a]) - eye[a]) / dir[a];
      const p = eye.map((e, k) => e + t * dir[k]);
      const inside = t > 0 && [0, 1, 2].every((b) => b === a ||
        (p[b] >= box.lo[b] - 1e-9 && p[b] <= box.hi[b] + 1e-9));
      if (inside && t < best) [best, face] = [t, { axis: a, high }];
    }
  }
  return face;
}

test('CropDrag_PickedFaceIsTheNearestOneTheRayMeets', () => {
  const box = worldBox(volume);
  box.lo[0] += 10;
  box.hi[2] -= 20;
  let hits = 0, misses = 0;
  for (const azimuth of [0, 40, 135, 250]) {
    const c = new OrbitCamera(volume);
    c.orbit(azimuth, 12);
    for (let py = 0; py < H; py += 8) {
      for (let px = 0; px < W; px += 8) {
        const want = bruteForce(c, box, px, py);
        assert.deepEqual(pickBoxFace(c, volume, box, px, py, W, H), want, `${azimuth} ${px},${py}`);
        if (want) hits += 1; else misses += 1;
      }
    }
  }
  assert.ok(hits > 100 && misses > 100, `hits ${hits}, misses ${misses}`);
});

test('CropDrag_AFaceFollowsThePointerAlongItsImage', () => {
  let followed = 0;
  for (const azimuth of [20, 110, 200]) {
    const c = new OrbitCamera(volume);
    c.orbit(azimuth, 20);
    const target = c.target();
    for (let axis = 0; axis < 3; ++axis) {
      const w = [0, 0, 0];
      w[axis] = 1;
      const n = directionToPhysical(volume, w);
      const p0 = project(c, target);
      const image = sub(project(c, target.map((v, k) => v + n[k])), p0);
      const len = Math.hypot(image[0], image[1]);
      if (len < 0.5 / c.mmPerPixel(W, H)) continue;
      const along = [image[0] / len, image[1] / len];
      const mouse = [3 * along[0] - 2 * along[1], 3 * along[1] + 2 * along[0]];
      const t = faceDragMm(c, volume, { axis, high: true }, mouse[0], mouse[1], W, H);
      const d = sub(project(c, target.map((v, k) => v + t * n[k])), p0);
      assert.ok(Math.abs(d[0] * along[0] + d[1] * along[1] - 3) < 0.05, `${azimuth} ${axis}`);
      followed += 1;
    }
  }
  assert.ok(followed >= 6, `followed ${followed}`);
});

test('CropDrag_AFaceSeenHeadOnMovesAwayWhenDraggedUp', () => {
  const c = new OrbitCamera(volume);  // looks along world +y (posterior)
  const fw = sub(physicalToWorld(volume, c.forward()), physicalToWorld(volume, [0, 0, 0]));
  assert.ok(Math.abs(fw[1] - 1) < 1e-9, `forward ${fw}`);
  const t = faceDragMm(c, volume, { axis: 1, high: false }, 0, -10, W, H);
  assert.ok(Math.abs(t - 10 * c.mmPerPixel(W, H)) < 1e-9, `t ${t}`);
});

test('CropDrag_FacesStayInsideTheLimitsAndOffTheOppositeFace', () => {
  const limits = { lo: [0, 0, 0], hi: [100, 80, 60] };
  const start = { lo: [10, 10, 10], hi: [90, 70, 50] };
  assert.equal(moveBoxFace(start, { axis: 0, high: true }, -15, limits).hi[0], 75);
  assert.equal(moveBoxFace(start, { axis: 1, high: false }, 25, limits).lo[1], 35);
  assert.equal(moveBoxFace(start, { axis: 2, high: true }, 40, limits).hi[2], 60);
  assert.equal(moveBoxFace(start, { axis: 2, high: false }, -40, limits).lo[2], 0);
  assert.equal(moveBoxFace(start, { axis: 0, high: false }, 500, limits, 2).lo[0], 88);
  assert.deepEqual(start.lo, [10, 10, 10], 'the start box is left alone');
});

// The outline drawn over the frame: camera.projectToPixel against the
// independent projection above and against the pixel's own ray; 12 edges
// whose ends are the box corners' images; the whole box in view at the
// fitted distance.
test('CropOutline_EdgesAreTheImagesOfTheBoxCorners', () => {
  for (const [az, el] of [[0, 0], [35, 20], [-120, -50]]) {
    const c = new OrbitCamera(volume);
    c.orbit(az, el);
    for (const [px, py] of [[0.5, 0.5], [W / 2, H / 3], [W - 3, H - 7]]) {
      const onRay = c.eye().map((e, a) => e + 250 * c.rayDirection(px, py, W, H)[a]);
      const back = c.projectToPixel(onRay, W, H);
      assert.ok(Math.abs(back[0] - (px + 0.5)) < 1e-6 && Math.abs(back[1] - (py + 0.5)) < 1e-6,
                `pixel ${px},${py} projects back to ${back}`);
      const ref = project(c, onRay);
      assert.ok(Math.abs(ref[0] - back[0]) < 1e-6 && Math.abs(ref[1] - back[1]) < 1e-6);
    }
    assert.equal(c.projectToPixel(c.eye().map((e, a) => e - 10 * c.forward()[a]), W, H), null);
    const box = worldBox(volume);
    const segments = boxOutlineSegments(c, volume, box, W, H);
    assert.equal(segments.length, 12);
    const corners = [];
    for (let k = 0; k < 8; ++k) {
      const w = [0, 1, 2].map((a) => ((k >> a) & 1 ? box.hi[a] : box.lo[a]));
      const p = worldToPhysical(volume, w);
      const round = physicalToWorld(volume, p);
      assert.ok(round.every((v, a) => Math.abs(v - w[a]) < 1e-9), 'world -> physical -> world');
      corners.push(project(c, p));
    }
    for (const [x0, y0, x1, y1] of segments) {
      for (const [x, y] of [[x0, y0], [x1, y1]]) {
        assert.ok(corners.some(([cx, cy]) => Math.abs(cx - x) < 1e-6 && Math.abs(cy - y) < 1e-6));
        if (az === 0 && el === 0) assert.ok(x >= 0 && x <= W && y >= 0 && y <= H, `${x},${y} in view`);
      }
      assert.ok(Math.hypot(x1 - x0, y1 - y0) > 1, 'an edge is a segment, not a point');
    }
  }
});

// The page's orbit camera (client/web/public/camera.js) against the
// conventions of server/raycast/camera.{h,cc} it mirrors: the anatomical
// default view, an orthonormal frame, the fitted distance, picks on the
// orbit-centre plane, and drag offsets that follow the pointer exactly.
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const { OrbitCamera, kFovDeg } = await import(
  pathToFileURL(path.join(here, '../../client/web/public/camera.js')).href);

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const near = (a, b, tol, what) => a.forEach((v, i) =>
  assert.ok(Math.abs(v - b[i]) <= tol, `${what}: ${a} vs ${b}`));

// A 101 x 81 x 61 volume, 2 x 2.5 x 3 mm voxels: extent 200 x 200 x 180 mm.
const identity = { dims: [101, 81, 61], spacing_mm: { x: 2, y: 2.5, z: 3 },
                   direction: [1, 0, 0, 0, 1, 0, 0, 0, 1] };
// The same box stored mirrored along i (det -1).
const mirrored = { ...identity, direction: [-1, 0, 0, 0, 1, 0, 0, 0, 1] };

test('OrbitCamera_DefaultIsAnteriorViewHeadUp', () => {
  const c = new OrbitCamera(identity);
  near(c.forward(), [0, 1, 0], 1e-12, 'looks posterior (+y)');
  near(c.up(), [0, 0, 1], 1e-12, 'superior up');
  near(c.right(), [1, 0, 0], 1e-12, "the patient's left (+x) on the right");
  near(c.target(), [100, 100, 90], 1e-12, 'orbit centre = box centre');
});

test('OrbitCamera_MirroredVolumeStillShowsLeftOnTheRight', () => {
  const c = new OrbitCamera(mirrored);
  // Physical direction of world left (+x): D^T (1,0,0) = (-1, 0, 0).
  assert.ok(dot(c.right(), [-1, 0, 0]) > 0.999);
});

test('OrbitCamera_FrameIsOrthonormalAtAnyPose', () => {
  const c = new OrbitCamera(identity);
  for (const [az, el] of [[0, 0], [37, 12], [-120, -80], [179, 89]]) {
    c.orbit(az - c.azimuthDeg, el - c.elevationDeg);
    const [f, u, r] = [c.forward(), c.up(), c.right()];
    for (const v of [f, u, r]) assert.ok(Math.abs(dot(v, v) - 1) < 1e-12);
    for (const [a, b] of [[f, u], [u, r], [r, f]]) assert.ok(Math.abs(dot(a, b)) < 1e-12);
  }
});

test('OrbitCamera_ElevationStopsShortOfThePoles', () => {
  const c = new OrbitCamera(identity);
  c.orbit(0, 500);
  assert.equal(c.elevationDeg, 89);
  c.orbit(400, -1000);
  assert.equal(c.elevationDeg, -89);
  assert.ok(c.azimuthDeg >= -180 && c.azimuthDeg < 180);
});

test('OrbitCamera_FitDistanceKeepsEveryCornerInView', () => {
  const c = new OrbitCamera(identity);
  const tanHalf = Math.tan((kFovDeg / 2) * Math.PI / 180);
  const worst = (distance) => {
    c.distanceMm = distance;
    let m = 0;
    for (let k = 0; k < 8; ++k) {
      const corner = [k & 1 ? 200 : 0, k & 2 ? 200 : 0, k & 4 ? 180 : 0];
      const v = sub(corner, c.eye());
      const depth = dot(v, c.forward());
      m = Math.max(m, Math.abs(dot(v, c.right())) / (depth * tanHalf),
                   Math.abs(dot(v, c.up())) / (depth * tanHalf));
    }
    return m;  // largest |ndc| over the corners
  };
  const fit = c.fitDistanceMm();
  assert.ok(worst(fit) < 1, 'a corner is out of view at the fitted distance');
  assert.ok(worst(fit / 1.05) > 0.999, 'the fit is not tight (5% margin)');
});

test('OrbitCamera_CentrePixelPicksTheOrbitCentre', () => {
  const c = new OrbitCamera(identity);
  c.orbit(30, 20);
  // Pixel (w/2, h/2) of an odd-sized frame is exactly on the axis.
  near(c.pickPointMm(128, 64, 257, 129), c.target(), 1e-9, 'centre pick');
  assert.ok(c.insideVolume(c.target()));
  assert.ok(!c.insideVolume(c.pickPointMm(0, 0, 257, 129)), 'a corner pixel misses the box');
});

test('OrbitCamera_DragOffsetFollowsThePointerOnThePickPlane', () => {
  const c = new OrbitCamera(identity);
  c.orbit(-50, 35);
  c.zoom(1.7);
  for (const [w, h] of [[256, 256], [640, 360]]) {
    const start = c.pickPointMm(100, 90, w, h);
    const end = c.pickPointMm(137, 61, w, h);
    near(c.dragOffsetMm(37, -29, w, h), sub(end, start), 1e-9, `${w}x${h}`);
  }
});

test('OrbitCamera_ToProtoCarriesThePose', () => {
  const c = new OrbitCamera(identity);
  c.orbit(10, -5);
  const p = c.toProto();
  assert.deepEqual([p.azimuth_deg, p.elevation_deg], [10, -5]);
  assert.ok(Math.abs(p.distance_mm - c.fitDistanceMm()) < 1e-9);
});

// The web viewer's workspace maths (client/web/public): pan and zoom about
// the pointer (camera.js), the slice planes through a point
// (slice_planes.js) and following a grab (grab_follow.js), canvases fitted to their panes (pane_fit.js), the
// window presets (window_presets.js) and the single-key shortcuts
// (view_keys.js, typing_target.js).
import assert from 'node:assert/strict';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const load = (name) => import(pathToFileURL(path.join(here, '../../client/web/public', name)).href);
const { OrbitCamera } = await load('camera.js');
const { clampToSlice, grabTargetMm, planesThrough } = await load('slice_planes.js');
const { GrabFollow } = await load('grab_follow.js');
const { fitContain, frameSizeForPane } = await load('pane_fit.js');
const { kWindowPresets, presetNameOf, windowPreset } = await load('window_presets.js');
const { kShortcutList, viewKey } = await load('view_keys.js');
const { takesTyping } = await load('typing_target.js');
const { undoKey } = await load('undo_keys.js');

const near = (a, b, tol, what) => a.forEach((v, i) =>
  assert.ok(Math.abs(v - b[i]) <= tol, `${what}: ${a} vs ${b}`));

// 101 x 81 x 61 voxels of 2 x 2.5 x 3 mm, axes permuted and flipped (an
// oblique-free but non-identity direction), turned and panned already.
function camera() {
  const c = new OrbitCamera({ dims: [101, 81, 61], spacing_mm: { x: 2, y: 2.5, z: 3 },
                              direction: [0, 1, 0, -1, 0, 0, 0, 0, 1],
                              origin_lps_mm: { x: 10, y: -20, z: 30 } });
  c.orbit(35, -20);
  c.panMm = [12, -7];
  return c;
}
const kFrames = [[512, 384], [300, 500], [256, 256]];

test('zoomAbout keeps the orbit-plane point under the pointer at the same pixel', () => {
  for (const [w, h] of kFrames) {
    for (const [px, py] of [[10, 20], [w - 30, h / 2], [w / 2 - 0.5, h / 2 - 0.5], [w - 1, h - 1]]) {
      for (const factor of [1.5, 0.6, 1e6, 1e-6]) {  // the last two clamp the distance
        const c = camera();
        const point = c.pickPointMm(px, py, w, h);
        const distance = c.distanceMm;
        c.zoomAbout(factor, px, py, w, h);
        assert.notEqual(c.distanceMm, distance, 'the zoom did not move the eye');
        near(c.projectToPixel(point, w, h), [px + 0.5, py + 0.5], 1e-6,
             `${w}x${h} pixel (${px}, ${py}) zoom ${factor}`);
        near(c.pickPointMm(px, py, w, h), point, 1e-6, 'the pick after the zoom');
      }
    }
  }
});

test('zoomAbout at the frame centre does not pan; off centre it pans towards the pointer', () => {
  const c = camera();
  c.zoomAbout(2, 255.5, 191.5, 512, 384);
  near(c.panMm, [12, -7], 1e-9, 'pan after a centred zoom');
  const d = camera();
  d.zoomAbout(2, 500, 10, 512, 384);  // up and right: closer pans right (+x) and up (+y)
  assert.ok(d.panMm[0] > 12 && d.panMm[1] > -7, `pan ${d.panMm}`);
  const e = camera();
  e.zoomAbout(0.5, 500, 10, 512, 384);  // moving away pans the other way
  assert.ok(e.panMm[0] < 12 && e.panMm[1] < -7, `pan ${e.panMm}`);
});

test('panByPixels moves the picture with the pointer', () => {
  for (const [w, h] of kFrames) {
    const c = camera();
    const point = c.pickPointMm(100, 80, w, h);
    c.panByPixels(37, -21, w, h);
    near(c.projectToPixel(point, w, h), [137.5, 59.5], 1e-6, `${w}x${h}`);
    const proto = c.toProto();
    assert.deepEqual([proto.pan_mm.x, proto.pan_mm.y, proto.pan_mm.z], [...c.panMm, 0]);
  }
});

test('the named planes through a point, the grab target and the clamp', () => {
  assert.deepEqual(planesThrough({ x: -12.5, y: 40, z: 7.25 }),
                   { axial: 7.25, coronal: 40, sagittal: -12.5 });
  assert.deepEqual(grabTargetMm([1, 2, 3], null), { x: 1, y: 2, z: 3 });
  assert.deepEqual(grabTargetMm([1, 2, 3], { x: 10, y: -2, z: 0.5 }), { x: 11, y: 0, z: 3.5 });
  const g = { min_offset_mm: -50, max_offset_mm: 80 };
  assert.equal(clampToSlice(100, g), 80);
  assert.equal(clampToSlice(-60, g), -50);
  assert.equal(clampToSlice(3, g), 3);
  assert.equal(clampToSlice(1e9, undefined), 1e9);
});

test('the planes follow the held grab and rest where a release leaves the tissue', () => {
  const at = [];
  const follow = new GrabFollow((p) => at.push([p.x, p.y, p.z]));
  const frame = (seq, point) => follow.frame({ last_sequence: seq, grab_point_mm: point });
  follow.grab(5);
  frame(4, [9, 9, 9]);  // an earlier grab's frame
  assert.deepEqual(at, []);
  frame(5, [1, 2, 3]);
  follow.drag({ x: 10, y: 0, z: 0 });
  frame(6, [1, 2, 3]);
  follow.drag({ x: 20, y: 0, z: 0 });  // no frame since: the release decides
  follow.release(false);
  frame(7, [1, 2, 3]);  // the released grab's late frame moves nothing
  assert.deepEqual(at, [[1, 2, 3], [11, 2, 3], [1, 2, 3]]);
  follow.grab(8);
  frame(8, [0, 0, 0]);
  follow.drag({ x: 0, y: 5, z: 0 });
  follow.release(true);  // kept: the drag's end
  assert.deepEqual(at.at(-1), [0, 5, 0]);
  at.length = 0;
  follow.grab(10);
  follow.drag({ x: 0, y: 0, z: 4 });
  follow.release(true);  // before any frame named the point
  assert.deepEqual(at, []);
  frame(9, [7, 7, 7]);  // the last grab's
  frame(11, [1, 1, 1]);
  frame(12, [1, 1, 1]);
  assert.deepEqual(at, [[1, 1, 5]]);
});

test('a canvas fits its pane with its aspect; the frame takes the pane\'s shape', () => {
  assert.deepEqual(fitContain(800, 600, 512, 512), { width: 600, height: 600 });
  assert.deepEqual(fitContain(300, 900, 200, 100), { width: 300, height: 150 });
  assert.deepEqual(fitContain(0, 600, 512, 512), { width: 0, height: 0 });
  for (const [pw, ph, long] of [[740, 700, 512], [433, 800, 256], [1290, 980, 768], [10, 2000, 512]]) {
    const f = frameSizeForPane(pw, ph, long);
    assert.equal(Math.max(f.width, f.height), long, `${pw}x${ph}`);
    assert.ok(Number.isInteger(f.width) && Number.isInteger(f.height));
    if (Math.min(f.width, f.height) > 32) {
      assert.ok(Math.abs(f.width / f.height - pw / ph) < 1 / Math.min(f.width, f.height),
                `${pw}x${ph}: ${f.width}x${f.height}`);
    }
    assert.ok(Math.min(f.width, f.height) >= 32);
  }
  assert.deepEqual(frameSizeForPane(0, 0, 512), { width: 512, height: 512 });
});

test('the window presets and their keys', () => {
  assert.deepEqual(kWindowPresets.map((p) => [p.name, p.width, p.level]),
                   [['soft-tissue', 400, 40], ['bone', 1800, 400], ['lung', 1500, -600],
                    ['brain', 80, 40]]);
  assert.equal(windowPreset('lung').level, -600);
  assert.equal(windowPreset('liver'), null);
  assert.equal(presetNameOf({ width: 1800, level: 400 }), 'bone');
  assert.equal(presetNameOf({ width: 1800, level: 401 }), '');
  kWindowPresets.forEach((p, i) => assert.equal(viewKey({ key: String(i + 1) }), `window:${p.name}`));
});

test('single keys: plain letters act, modified ones and undo keys do not', () => {
  const cases = { r: 'reset-view', R: 'reset-view', s: 'slices', c: 'view-cut', o: 'tool:orbit',
                  g: 'tool:grab', p: 'tool:pin', '?': 'keys', x: null, F2: null, Escape: null };
  for (const [key, want] of Object.entries(cases)) {
    assert.equal(viewKey({ key, shiftKey: key === '?' }), want, key);
  }
  assert.equal(viewKey({ key: '?', shiftKey: true }), 'keys');
  for (const mod of ['ctrlKey', 'metaKey', 'altKey', 'shiftKey', 'repeat']) {
    assert.equal(viewKey({ key: 'r', [mod]: true }), null, mod);
  }
  // Ctrl+Z stays undo's, never a view key.
  assert.equal(viewKey({ key: 'z', ctrlKey: true }), null);
  assert.equal(undoKey({ key: 'z', ctrlKey: true }), 'undo');
  // The page lists every key it handles.
  const listed = kShortcutList.map(([k]) => k).join(' ');
  for (const k of ['1', '2', '3', '4', 'R', 'S', 'C', 'O / G / P', '?', 'Ctrl+Z', 'F2']) {
    assert.ok(listed.includes(k), `${k} is not listed`);
  }
});

test('keys typed into a field stay the field\'s; on a checkbox, range or select they act', () => {
  for (const type of ['text', 'number', 'date', 'search', undefined]) {
    assert.ok(takesTyping({ tagName: 'INPUT', type }), String(type));
  }
  assert.ok(takesTyping({ tagName: 'TEXTAREA' }));
  assert.ok(takesTyping({ tagName: 'DIV', isContentEditable: true }));
  for (const type of ['checkbox', 'radio', 'range', 'file']) {
    assert.ok(!takesTyping({ tagName: 'INPUT', type }), type);
  }
  assert.ok(!takesTyping({ tagName: 'SELECT' }));
  assert.ok(!takesTyping({ tagName: 'CANVAS' }));
  assert.ok(!takesTyping(null));
});

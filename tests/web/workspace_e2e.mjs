// The web viewer's workspace in headless Chromium, on a real vpm-server and
// gateway, at 1280 x 800 and 1920 x 1080: every control, the 3D view, the
// three slices and the status line inside the viewport with no page scroll
// (a screenshot of each size: BUILD/tests/web/workspace_WxH.png), the 3D
// frame asked in its pane's shape, the Keys and help list opened with "?";
// a right drag pans the picture by the drag, the wheel zooms about the
// pointer (the point under it stays), the window preset keys change the
// slices, a grab puts the three slice planes through the grabbed tissue and
// they follow the drag, and Shift+click puts them through the clicked point.
// Usage: node workspace_e2e.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';

import {
  canvasGrey, launchBrowser, meanAbsDiff, randomToken, runScenario, settled, signInWithForm,
  startGateway, startServer, testPaths, writeUsersFile,
} from './harness.mjs';
import { bestShift } from './image_shift.mjs';

// Frame pixels. A pan of the orbit-centre plane moves what the view cut
// leaves (the tissue at that plane) by the drag; the match is to a pixel,
// and tissue off the plane moves a little more or less (perspective).
const kPanTolerancePx = 3;
// The point under the pointer moves at most this far on a zoom about it
// (a zoom about the frame centre would move it (scale - 1) times its
// distance from the centre: tens of pixels here).
const kZoomDriftPx = 3;
const kMinSliceDiff = 1;  // mean |grey difference| a window change makes at least
const kPlaneToleranceMm = 0.01;  // a plane's position against the point it was sent through

const { build, source, out } = testPaths(process.argv);
const token = randomToken();
const aliceToken = randomToken();
const figures = {};
const step = (text) => console.log(`web_workspace: ${text}`);

// Every visible control and pane, with its box; the page's scroll sizes.
const kMustShow = ['#volume', '#frame-size', '#open', '#studies-toggle', '#cases-toggle',
  '#tools', 'input[value="grab"]', '#render', '#interactive-quality', '#overlay', '#keep-drag',
  '#undo', '#redo',
  '#reset-tissue', '#reset-view', '#refine-grab', '#tf-file', '#slices', '#slice-overlay',
  '#window-preset', '#window-width', '#window-level', '#view-cut', '#crop', '#clip-side',
  '#clip-at', '#clip-add', '#keys-toggle', '#frame', '#slice-axial', '#slice-coronal',
  '#slice-sagittal', '#status', '#mesh-info', '#sign-out'];

function layout(page) {
  return page.evaluate((mustShow) => {
    const boxes = [];
    const seen = new Set();
    const all = [...mustShow.map((s) => document.querySelector(s)),
                 ...document.querySelectorAll('header *, #picker *, #sidebar *, #views *, #bottom *')];
    for (const e of all) {
      if (!e || seen.has(e)) continue;
      seen.add(e);
      const r = e.getBoundingClientRect();
      const shown = r.width > 0 && r.height > 0 && getComputedStyle(e).visibility !== 'hidden';
      const name = e.id ? `#${e.id}` : `${e.tagName.toLowerCase()}${e.name ? `[${e.name}]` : ''}`;
      boxes.push({ name, shown, must: mustShow.some((s) => document.querySelector(s) === e),
                   left: r.left, top: r.top, right: r.right, bottom: r.bottom,
                   height: r.height, tag: e.tagName });
    }
    const d = document.documentElement;
    return { boxes, scrollWidth: d.scrollWidth, scrollHeight: d.scrollHeight,
             innerWidth, innerHeight };
  }, kMustShow);
}

// Asserts the workspace fits: no page scroll, every control and pane shown
// and inside the viewport, the panes apart, buttons one line high.
async function checkFits(page, size) {
  const l = await layout(page);
  assert.ok(l.scrollHeight <= l.innerHeight && l.scrollWidth <= l.innerWidth,
            `${size}: the page scrolls (${l.scrollWidth} x ${l.scrollHeight})`);
  for (const b of l.boxes) {
    if (b.must) assert.ok(b.shown, `${size}: ${b.name} is not shown`);
    if (!b.shown) continue;
    assert.ok(b.left >= -0.5 && b.top >= -0.5 && b.right <= l.innerWidth + 0.5 &&
              b.bottom <= l.innerHeight + 0.5, `${size}: ${b.name} is outside the viewport ` +
              `(${b.left}, ${b.top}, ${b.right}, ${b.bottom})`);
    if (b.tag === 'BUTTON') assert.ok(b.height < 30, `${size}: ${b.name} wraps (${b.height} px)`);
  }
  const clip = l.boxes.find((b) => b.name === '#clip-label');
  assert.ok(!clip.shown || clip.height < 22, `${size}: the clip label wraps`);
  const panes = ['#frame', '#slice-axial', '#slice-coronal', '#slice-sagittal', '#sidebar']
    .map((n) => l.boxes.find((b) => b.name === n) ?? null);
  const sidebar = await page.locator('#sidebar').boundingBox();
  panes[4] = { name: '#sidebar', left: sidebar.x, top: sidebar.y, right: sidebar.x + sidebar.width,
               bottom: sidebar.y + sidebar.height };
  for (let i = 0; i < panes.length; ++i) {
    for (let j = i + 1; j < panes.length; ++j) {
      const [a, b] = [panes[i], panes[j]];
      const apart = a.right <= b.left + 0.5 || b.right <= a.left + 0.5 ||
                    a.bottom <= b.top + 0.5 || b.bottom <= a.top + 0.5;
      assert.ok(apart, `${size}: ${a.name} and ${b.name} overlap`);
    }
  }
  const sidebarScroll = await page.evaluate(() => {
    const s = document.getElementById('sidebar');
    return s.scrollHeight - s.clientHeight;
  });
  assert.ok(sidebarScroll <= 0, `${size}: the controls' column scrolls by ${sidebarScroll} px`);
  const sizes = Object.fromEntries(panes.slice(0, 4).map((p) => [p.name,
    `${Math.round(p.right - p.left)}x${Math.round(p.bottom - p.top)}`]));
  step(`${size}: ${l.boxes.filter((b) => b.shown).length} elements inside the viewport, page ` +
       `${l.scrollWidth}x${l.scrollHeight}, canvases (CSS px) ${JSON.stringify(sizes)}`);
  figures[`canvases_${size}`] = sizes;
  return sizes;
}

// The 3D frame has its pane's shape, and the server sent that size.
async function checkFrameShape(page, size) {
  // After a window resize the page asks for the new shape once its resize
  // handler has run: read the canvas only once it has taken the pane's
  // aspect (else the frame awaited is the old size, which never comes).
  await page.waitForFunction(() => {
    const c = document.getElementById('frame');
    const box = c.parentElement;
    const want = box.clientWidth / box.clientHeight;
    return Math.abs(c.width / c.height - want) / want < 0.01;
  }, null, { timeout: 10000 });
  const s = await page.evaluate(() => {
    const c = document.getElementById('frame');
    const box = c.parentElement;
    return { w: c.width, h: c.height, boxW: box.clientWidth, boxH: box.clientHeight,
             long: Number(document.getElementById('frame-size').value) };
  });
  const h = await settled(page, `!h.interactive && h.width === ${s.w} && h.height === ${s.h}`);
  assert.equal(Math.max(s.w, s.h), s.long);
  const aspectError = Math.abs(s.w / s.h - s.boxW / s.boxH) / (s.boxW / s.boxH);
  step(`${size}: 3D pane ${s.boxW}x${s.boxH} CSS px, frame ${h.width}x${h.height} ` +
       `(aspect off by ${(100 * aspectError).toFixed(2)} %)`);
  assert.ok(aspectError < 0.01, `${size}: the frame's aspect is not the pane's`);
}

// "?" opens the Keys and help list, inside the viewport; Esc closes it.
async function checkKeysList(page, size) {
  await page.locator('#frame').hover();
  await page.keyboard.press('?');
  await page.waitForSelector('#keys', { state: 'visible', timeout: 5000 });
  const r = await page.locator('#keys').boundingBox();
  const v = page.viewportSize();
  assert.ok(r.x >= 0 && r.y >= 0 && r.x + r.width <= v.width && r.y + r.height <= v.height,
            `${size}: the keys list is outside the viewport ${JSON.stringify(r)}`);
  const listed = await page.locator('#keys-list dt').allTextContents();
  for (const k of ['1', '2', '3', '4', 'R', 'S', 'C', '?', 'Ctrl+Z', 'Right / middle drag']) {
    assert.ok(listed.includes(k), `${size}: the keys list lacks ${k}`);
  }
  await page.screenshot({ path: path.join(out, `workspace_${size}_keys.png`) });
  await page.keyboard.press('Escape');
  await page.waitForSelector('#keys', { state: 'hidden', timeout: 5000 });
  step(`${size}: "?" lists ${listed.length} keys and gestures inside the viewport`);
}

// The frame canvas's geometry: its CSS box and frame pixels per CSS pixel.
const frameBox = (page) => page.evaluate(() => {
  const c = document.getElementById('frame');
  const r = c.getBoundingClientRect();
  return { left: r.left, top: r.top, cssW: r.width, cssH: r.height, w: c.width, h: c.height,
           sx: c.width / r.width, sy: c.height / r.height };
});

async function checkPan(page) {
  const b = await frameBox(page);
  const before = await canvasGrey(page);
  const from = [b.left + 0.5 * b.cssW, b.top + 0.5 * b.cssH];
  const drag = [60, 40];  // CSS px
  await page.mouse.move(...from);
  await page.mouse.down({ button: 'right' });
  await page.mouse.move(from[0] + drag[0], from[1] + drag[1], { steps: 6 });
  await page.mouse.up({ button: 'right' });
  await settled(page, '!h.interactive');
  const after = await canvasGrey(page);
  const want = [drag[0] * b.sx, drag[1] * b.sy];
  const c = [b.w / 2, b.h / 2];
  const got = bestShift(before.grey, after.grey, b.w, b.h, c, 1, 40, 60);
  const pan = await page.evaluate(() => window.vpmViewer.camera.panMm);
  step(`right drag ${drag} CSS px: picture moved (${got.shift.map((v) => v.toFixed(1))}) frame px, ` +
       `expected (${want.map((v) => v.toFixed(1))}); pan_mm (${pan.map((v) => v.toFixed(1))})`);
  figures.pan_error_px = Math.hypot(got.shift[0] - want[0], got.shift[1] - want[1]);
  assert.ok(figures.pan_error_px <= kPanTolerancePx, `the pan moved the picture by ${got.shift}`);
  const menu = await page.evaluate(() => {
    const e = new MouseEvent('contextmenu', { bubbles: true, cancelable: true });
    return document.getElementById('frame').dispatchEvent(e);
  });
  assert.equal(menu, false, 'the 3D view opens a context menu');
}

async function checkZoomAboutPointer(page) {
  const b = await frameBox(page);
  const before = await canvasGrey(page);
  // Up and right of the centre, on the abdomen.
  const c = [0.62 * b.w, 0.4 * b.h];
  const d0 = await page.evaluate(() => window.vpmViewer.camera.distanceMm);
  await page.mouse.move(b.left + c[0] / b.sx, b.top + c[1] / b.sy);
  await page.mouse.wheel(0, -300);
  await settled(page, '!h.interactive');
  const d1 = await page.evaluate(() => window.vpmViewer.camera.distanceMm);
  const scale = d0 / d1;
  const after = await canvasGrey(page);
  const got = bestShift(before.grey, after.grey, b.w, b.h, c, scale, 30, 40);
  const centreZoomDrift = (scale - 1) * Math.hypot(c[0] - b.w / 2, c[1] - b.h / 2);
  figures.zoom_drift_px = Math.hypot(...got.shift);
  step(`wheel zoom x${scale.toFixed(2)} about frame pixel (${c.map((v) => v.toFixed(0))}): the ` +
       `point under it moved ${figures.zoom_drift_px.toFixed(1)} px (match error ` +
       `${got.error.toFixed(1)} grey; about the centre it would move ${centreZoomDrift.toFixed(0)} px)`);
  assert.ok(scale > 1.3, `the wheel zoomed by ${scale}`);
  assert.ok(centreZoomDrift > 5 * kZoomDriftPx, 'the pointer is too near the centre to tell');
  assert.ok(figures.zoom_drift_px <= kZoomDriftPx, `the point under the pointer moved ${got.shift}`);
}

async function checkWindowPresets(page) {
  const greys = {};
  for (const [key, name, width] of [['1', 'soft-tissue', 400], ['2', 'bone', 1800],
                                    ['3', 'lung', 1500], ['4', 'brain', 80]]) {
    await page.keyboard.press(key);
    await settled(page, `!h.interactive && h.slices.length === 3 && ` +
                        `h.slices.every((s) => s.geometry.window.width === ${width})`);
    assert.equal(await page.inputValue('#window-preset'), name);
    greys[name] = await canvasGrey(page, 'slice-axial');
  }
  const diffs = ['bone', 'lung', 'brain'].map((n) => meanAbsDiff(greys['soft-tissue'], greys[n]));
  step(`window presets: axial mean |grey difference| from soft tissue: bone ` +
       `${diffs[0].toFixed(1)}, lung ${diffs[1].toFixed(1)}, brain ${diffs[2].toFixed(1)}`);
  diffs.forEach((d) => assert.ok(d > kMinSliceDiff, `a window preset did not change the slice (${d})`));
  await page.keyboard.press('1');
  await settled(page, '!h.interactive && h.slices[0].geometry.window.width === 400');
}

// Each slice plane's position (offset_mm) against the point's coordinate
// on its normal (axial z, coronal y, sagittal x).
function planesOff(h, point) {
  const axis = { axial: 2, coronal: 1, sagittal: 0 };
  return h.slices.map((s) => Math.abs(s.geometry.offset_mm - point[axis[s.view]]));
}

async function checkSlicesFollowGrab(page, sentDrags) {
  const b = await frameBox(page);
  await page.check('input[name="tool"][value="grab"]');
  const c = [b.left + 0.45 * b.cssW, b.top + 0.5 * b.cssH];
  await page.mouse.move(...c);
  await page.mouse.down();
  const targets = [];
  for (const [dx, dy] of [[20, -12], [45, 10]]) {
    await page.mouse.move(c[0] + dx, c[1] + dy, { steps: 6 });
    const h = await settled(page, '!h.interactive && h.grab_point_mm && h.slices.length === 3 && ' +
                            'h.slices.every((s) => Math.abs(s.geometry.offset_mm - ' +
                            'v.slices.at[s.view]) < 1e-6)', 60000);
    const o = sentDrags.at(-1);
    const target = h.grab_point_mm.map((v, i) => v + [o.x, o.y, o.z][i]);
    const off = planesOff(h, target);
    step(`grab held, dragged (${dx}, ${dy}) CSS px: grab point (${h.grab_point_mm.map((v) =>
      v.toFixed(1))}) + offset (${[o.x, o.y, o.z].map((v) => v.toFixed(1))}) mm; planes at ` +
      `${h.slices.map((s) => `${s.view} ${s.geometry.offset_mm.toFixed(2)}`).join(', ')} ` +
      `(off by at most ${Math.max(...off).toExponential(1)} mm)`);
    off.forEach((e) => assert.ok(e <= kPlaneToleranceMm, `a plane misses the grab: ${off}`));
    targets.push(target);
  }
  assert.ok(Math.hypot(...targets[1].map((v, i) => v - targets[0][i])) > 5,
            'the second drag did not move the grab target');
  await page.screenshot({ path: path.join(out, 'workspace_grab.png') });
  await page.mouse.up();
  await settled(page, '!h.interactive');
  await page.check('input[name="tool"][value="orbit"]');

  // Shift+click: the planes through the orbit-centre plane's point there.
  // Whole CSS pixels, so the page's frame pixel is the one computed here.
  const at = [Math.round(b.left + (0.3 * b.w) / b.sx), Math.round(b.top + (0.6 * b.h) / b.sy)];
  await page.keyboard.down('Shift');
  await page.mouse.click(...at);
  await page.keyboard.up('Shift');
  const point = await page.evaluate(([x, y]) => {
    const cam = window.vpmViewer.camera;
    const c = document.getElementById('frame');
    const r = c.getBoundingClientRect();
    const px = Math.floor(((x - r.left) * c.width) / r.width);
    const py = Math.floor(((y - r.top) * c.height) / r.height);
    return cam.worldPoint(cam.pickPointMm(px, py, c.width, c.height));
  }, at);
  const h = await settled(page, `!h.interactive && h.slices.length === 3 && ` +
                          `Math.abs(h.slices[0].geometry.offset_mm - ${point[2]}) < 1e-3`);
  const off = planesOff(h, point);
  step(`Shift+click: planes through (${point.map((v) => v.toFixed(1))}) mm, off by at most ` +
       `${Math.max(...off).toExponential(1)} mm`);
  off.forEach((e) => assert.ok(e <= kPlaneToleranceMm, `a plane misses the clicked point: ${off}`));
}

async function main() {
  const usersFile = writeUsersFile(path.join(out, 'workspace_users.txt'), { alice: aliceToken });
  const server = await startServer({ build, out, token, logName: 'workspace_server.log',
                                     args: ['--users', usersFile] });
  const gateway = await startGateway({ source, out, serverAddress: server.address, token,
                                       logName: 'workspace_gateway.log',
                                       args: ['--users', usersFile] });
  const browser = await launchBrowser(source);
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 }, bypassCSP: true });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  const sentDrags = [];
  page.on('websocket', (ws) => ws.on('framesent', ({ payload }) => {
    try {
      const drag = JSON.parse(String(payload))?.event?.drag;
      if (drag) sentDrags.push(drag.offset_mm);
    } catch { /* not JSON */ }
  }));
  await signInWithForm(page, gateway.url, aliceToken);
  await page.waitForSelector('#server-state[data-state="up"]', { timeout: 15000 });
  assert.ok(await page.isChecked('#slices'), 'the slices are not on at start');
  await checkFits(page, '1280x800');  // before any volume: the empty workspace fits too

  await page.selectOption('#volume', 'source:phantom:abdomen?size=128');
  await page.selectOption('#frame-size', '384');
  await page.click('#open');
  await settled(page, '!h.interactive && h.slices.length === 3', 120000);
  await checkFrameShape(page, '1280x800');
  await checkFits(page, '1280x800');
  await page.screenshot({ path: path.join(out, 'workspace_1280x800.png') });
  await checkKeysList(page, '1280x800');
  await checkPan(page);
  await checkZoomAboutPointer(page);
  await checkWindowPresets(page);
  await checkSlicesFollowGrab(page, sentDrags);

  await page.setViewportSize({ width: 1920, height: 1080 });
  await page.keyboard.press('r');  // reset view
  await checkFrameShape(page, '1920x1080');
  await checkFits(page, '1920x1080');
  await page.screenshot({ path: path.join(out, 'workspace_1920x1080.png') });
  await checkKeysList(page, '1920x1080');

  // S turns the slices off: the 3D view takes their room and its shape.
  await page.keyboard.press('s');
  await settled(page, '!h.interactive && h.slices.length === 0');
  await checkFrameShape(page, '1920x1080 slices off');
  await page.keyboard.press('s');
  await settled(page, '!h.interactive && h.slices.length === 3');

  assert.deepEqual(pageErrors, [], 'the page threw');
  fs.writeFileSync(path.join(out, 'workspace_e2e.json'), JSON.stringify(figures, null, 2));
  step(`figures ${JSON.stringify(figures)}`);
  await browser.close();
}

runScenario('web_workspace', main);

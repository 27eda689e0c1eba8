// End to end in headless Chromium: vpm-server and the gateway on ephemeral
// ports with two users, alice signs in through the form (HttpOnly,
// SameSite=Strict cookie), the page opens the 128^3 phantom at 256 x 256,
// the first frame is
// not blank, an orbit drag changes it, a grab-and-drag deforms the tissue
// (the server reports max_displacement_mm > 0 and the still frame while
// holding differs from the one before), release brings it back, refine,
// zoom and MIP work, the Crop tool drags a face of the crop box, the token never reaches the browser, a second browser
// without a cookie (sent to sign in, WebSocket refused) or signed in as bob
// (NOT_FOUND, as for a missing one) cannot reach alice's session, stopping the server
// shows a clear message, and restarting it brings the view back.
// Cases (the server keeps them in a --state-dir): after a kept drag Ctrl+Z
// takes it back (fewer events in effect, the largest displacement back to
// what it was, the frame changes) and Ctrl+Shift+Z brings it back (the same
// displacement within 1e-3 mm, the same frame); the Cases panel lists
// alice's cases (not to bob), renames one, opens it again with its
// deformation and deletes another; the restarted server's page is back in
// the same case with the same largest displacement.
// Usage: node viewer_e2e.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';

import {
  canvasGrey, freshStateDir, launchBrowser, meanAbsDiff, pressUndoKeys, randomToken, refreshCases,
  settled, signInWithForm, startGateway, startServer, writeUsersFile,
  runScenario, stopChild, testPaths,
} from './harness.mjs';

// Grey-level thresholds (0..255, mean over the 256 x 256 canvas). A blank
// or uniform canvas has variance 0; the phantom's first frame has hundreds.
const kMinVariance = 50;
const kMinOrbitDiff = 2;   // a 30-degree turn moves most of the image
const kMinGrabDiff = 0.2;  // a local deformation moves a small area
// A case replayed (after an undo and redo, a reopen, a restart) has the
// largest displacement it had, mm.
const kReplayToleranceMm = 1e-3;

const { build, source, out } = testPaths(process.argv);
const token = randomToken();  // the viewer token (and the server's user `default`)
const aliceToken = randomToken();
const bobToken = randomToken();
const figures = {};
const step = (text) => console.log(`web_e2e: ${text}`);

async function dragOnCanvas(page, from, to, steps) {
  await page.mouse.move(from[0], from[1]);
  await page.mouse.down();
  await page.mouse.move(to[0], to[1], { steps });
}

// Opens a WebSocket to the gateway from `page` (its cookies, its origin),
// sends `message` once open and resolves with the first JSON reply of a
// type in `until`, or {refused: true} when the upgrade is refused.
function rawSocket(page, message, until = ['error', 'opened']) {
  return page.evaluate(([m, types]) => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    const replies = [];
    ws.onopen = () => ws.send(JSON.stringify(m));
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      const r = JSON.parse(e.data);
      if (types.includes(r.type)) {
        resolve(r);
        ws.close();
      }
      replies.push(r);
    };
    ws.onclose = () => resolve({ refused: true, replies });
    setTimeout(() => resolve({ timeout: true, replies }), 15000);
  }), [message, until]);
}

// Slice pixels change by at least this much (mean |grey difference|) when
// a slice scrolls 5 mm, its window changes or its tissue is dragged.
const kMinSliceDiff = 1;
// Slicer's CT-Bone volume property, as Slicer saves it.
const kCtBoneVp = '1\n1\n0.9\n0.1\n0.2\n10\n' +
  '8 -3024 0 -16.4458 0 641.385 0.715686 3071 0.705882\n4 0 1 255 1\n' +
  '16 -3024 0 0 0 -16.4458 0.729412 0.254902 0.301961 641.385 0.905882 0.815686 0.552941 ' +
  '3071 1 1 1\n';

// The page point (CSS pixels) of canvas `id` where soft tissue shows its
// strongest edge: in the canvas's central half, the pixel whose grey (of
// `grey`, canvasGrey's) is that of soft tissue in the window (neither air
// nor bone) with the largest step to its neighbours two pixels away.
async function softTissueEdge(page, id, grey) {
  const box = await page.locator(`#${id}`).boundingBox();
  const { width, height } = grey;
  const g = (x, y) => grey.grey[y * width + x];
  let best = { step: -1, x: width / 2, y: height / 2 };
  for (let y = Math.floor(height / 4); y < (3 * height) / 4; ++y) {
    for (let x = Math.floor(width / 4); x < (3 * width) / 4; ++x) {
      if (g(x, y) < 60 || g(x, y) > 160) continue;
      const step = Math.abs(g(x + 2, y) - g(x - 2, y)) + Math.abs(g(x, y + 2) - g(x, y - 2));
      if (step > best.step) best = { step, x, y };
    }
  }
  return [box.x + ((best.x + 0.5) * box.width) / width, box.y + ((best.y + 0.5) * box.height) / height];
}

// The slices beside the 3D view: three slices show and are not blank, the wheel scrolls
// one, the window changes it, a grab on a slice deforms the tissue there;
// then the crop box, the clip plane and an uploaded Slicer .vp each change
// the 3D frame.
async function checkSlicesAndCuts(page, sentClips) {
  await page.check('#slices');
  let h = await settled(page, '!h.interactive && h.slices.length === 3');
  assert.deepEqual(h.slices.map((s) => s.view), ['axial', 'coronal', 'sagittal']);
  const grey = {};
  for (const view of ['axial', 'coronal', 'sagittal']) {
    grey[view] = await canvasGrey(page, `slice-${view}`);
    step(`${view} slice ${h.slices.find((s) => s.view === view).width}x` +
         `${h.slices.find((s) => s.view === view).height}: variance ${grey[view].variance.toFixed(1)}`);
    assert.ok(grey[view].variance > kMinVariance, `the ${view} slice looks blank`);
  }
  await page.screenshot({ path: path.join(out, 'web_viewer_slices.png') });

  // The wheel over the axial slice: 5 notches of one pixel size each.
  const at = h.slices[0].geometry.offset_mm;
  const axialBox = await page.locator('#slice-axial').boundingBox();
  await page.mouse.move(axialBox.x + axialBox.width / 2, axialBox.y + axialBox.height / 2);
  for (let i = 0; i < 5; ++i) {
    await page.mouse.wheel(0, 100);
    await page.waitForTimeout(40);
  }
  h = await settled(page, `!h.interactive && h.slices[0].geometry.offset_mm > ${at} + 2`);
  const scrolled = await canvasGrey(page, 'slice-axial');
  const scrollDiff = meanAbsDiff(grey.axial, scrolled);
  step(`wheel on the axial slice: ${at.toFixed(1)} -> ${h.slices[0].geometry.offset_mm.toFixed(1)} mm, ` +
       `mean |grey difference| ${scrollDiff.toFixed(2)}`);
  assert.ok(scrollDiff > kMinSliceDiff, `scrolling did not change the axial slice (${scrollDiff})`);
  assert.match(await page.textContent('#at-axial'), /mm/);

  // Window: W 1500 shows the soft tissue greyer.
  await page.fill('#window-width', '1500');
  await page.dispatchEvent('#window-width', 'change');
  h = await settled(page, '!h.interactive && h.slices[1].geometry.window.width === 1500');
  const windowed = await canvasGrey(page, 'slice-coronal');
  const windowDiff = meanAbsDiff(grey.coronal, windowed);
  step(`window W 1500: coronal mean |grey difference| ${windowDiff.toFixed(2)}`);
  assert.ok(windowDiff > kMinSliceDiff, `the window did not change the slice (${windowDiff})`);

  // Grab on the coronal slice, at an edge of soft tissue (where the plane
  // lies depends on the grabs before; its centre may be the spine, which
  // the skeleton holds still, or the inside of one organ, where a move
  // shows nothing), and drag within its plane.
  await page.check('input[name="tool"][value="grab"]');
  const c = await softTissueEdge(page, 'slice-coronal', windowed);
  step(`grab on the coronal slice at page pixel (${c.map((v) => v.toFixed(0)).join(', ')})`);
  await dragOnCanvas(page, c, [c[0] + 12, c[1] - 8], 8);
  h = await settled(page, '!h.interactive && h.max_displacement_mm > 0', 60000);
  const grabbed = await canvasGrey(page, 'slice-coronal');
  const sliceGrabDiff = meanAbsDiff(windowed, grabbed);
  step(`grab on the coronal slice: max_displacement_mm ${h.max_displacement_mm.toFixed(2)}, ` +
       `mean |grey difference| ${sliceGrabDiff.toFixed(2)}`);
  assert.ok(sliceGrabDiff > kMinGrabDiff, `the slice grab did not show (${sliceGrabDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_slice_grab.png') });
  await page.mouse.up();
  await settled(page, '!h.interactive');
  await page.check('input[name="tool"][value="orbit"]');

  // The crop box, the clip plane and an uploaded transfer function.
  let before3d = await canvasGrey(page);
  await page.check('#crop');
  const [x0, x1] = await page.evaluate(() => [Number(document.getElementById('crop-x0').value),
                                              Number(document.getElementById('crop-x1').value)]);
  await page.fill('#crop-x1', String(((x0 + x1) / 2).toFixed(1)));
  await page.dispatchEvent('#crop-x1', 'change');
  await settled(page, '!h.interactive');
  let after3d = await canvasGrey(page);
  const cropDiff = meanAbsDiff(before3d, after3d);
  step(`crop to half the x range: 3D mean |grey difference| ${cropDiff.toFixed(2)}`);
  assert.ok(cropDiff > kMinOrbitDiff, `the crop box did not change the frame (${cropDiff})`);
  // The box's outline is drawn over the frame: its edges' midpoints in view
  // are the outline's yellow (255, 210, 0).
  const outline = await page.evaluate(() => {
    const c = document.getElementById('frame');
    const rgba = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const edges = window.vpmViewer.cropOutline ?? [];
    let inView = 0, yellow = 0;
    for (const [x0, y0, x1, y1] of edges) {
      const [x, y] = [Math.round((x0 + x1) / 2), Math.round((y0 + y1) / 2)];
      if (x < 1 || y < 1 || x >= c.width - 1 || y >= c.height - 1) continue;
      inView += 1;
      let hit = false;
      for (let dy = -1; dy <= 1; ++dy) {
        for (let dx = -1; dx <= 1; ++dx) {
          const i = 4 * ((y + dy) * c.width + x + dx);
          hit ||= rgba[i] > 240 && Math.abs(rgba[i + 1] - 210) < 12 && rgba[i + 2] < 15;
        }
      }
      if (hit) yellow += 1;
    }
    return { edges: edges.length, inView, yellow };
  });
  step(`crop outline: ${outline.edges} edges, ${outline.yellow} of ${outline.inView} midpoints in view drawn`);
  assert.equal(outline.edges, 12, 'the crop box outline has 12 edges');
  assert.ok(outline.inView >= 4 && outline.yellow === outline.inView,
            `the crop outline is not drawn (${JSON.stringify(outline)})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_crop.png') });
  await page.uncheck('#crop');
  await settled(page, '!h.interactive');
  before3d = await canvasGrey(page);
  await page.selectOption('#clip-side', 'P');
  await settled(page, '!h.interactive');
  after3d = await canvasGrey(page);
  const clipDiff = meanAbsDiff(before3d, after3d);
  step(`clip plane (keep posterior of the centre): mean |grey difference| ${clipDiff.toFixed(2)}`);
  assert.ok(clipDiff > kMinOrbitDiff, `the clip plane did not change the frame (${clipDiff})`);
  // Several planes: keep the posterior one, place a superior one; both go
  // in one settings event and the frame changes again; Clear drops them.
  await page.click('#clip-add');
  await page.selectOption('#clip-side', 'S');
  await settled(page, '!h.interactive');
  const twoPlanes = sentClips[sentClips.length - 1];
  const twoDiff = meanAbsDiff(after3d, await canvasGrey(page));
  step(`two clip planes (${await page.textContent('#clip-kept')}): ` +
       `${twoPlanes.length} sent, mean |grey difference| from one plane ${twoDiff.toFixed(2)}`);
  assert.equal(twoPlanes.length, 2, `two clip planes expected, sent ${JSON.stringify(twoPlanes)}`);
  assert.deepEqual(twoPlanes.map((c) => [c.normal.x, c.normal.y, c.normal.z]), [[0, 1, 0], [0, 0, 1]]);
  assert.ok(twoDiff > kMinOrbitDiff, `the second clip plane did not change the frame (${twoDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_two_clips.png') });
  await page.click('#clip-clear');
  await page.selectOption('#clip-side', '');
  await settled(page, '!h.interactive');
  assert.equal(sentClips[sentClips.length - 1].length, 0, 'Clear planes left a plane');
  before3d = await canvasGrey(page);
  await page.setInputFiles('#tf-file', { name: 'MyBone.vp', mimeType: 'text/plain',
                                         buffer: Buffer.from(kCtBoneVp) });
  await page.waitForFunction(() => document.getElementById('render').value === 'dvr:uploaded',
                             null, { timeout: 15000 });
  await settled(page, '!h.interactive');
  after3d = await canvasGrey(page);
  const tfDiff = meanAbsDiff(before3d, after3d);
  step(`uploaded Slicer .vp (${await page.evaluate(() => window.vpmViewer.uploadedTf.name)}): ` +
       `mean |grey difference| ${tfDiff.toFixed(2)}`);
  assert.ok(tfDiff > kMinOrbitDiff, `the uploaded transfer function did not change the frame (${tfDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_uploaded_tf.png') });
  await page.uncheck('#slices');
  await settled(page, '!h.interactive && h.slices.length === 0');
}

// The Crop tool: from the reset view (which looks posterior, along world
// +y), pressing on the 3D view's centre picks the box's anterior face (y
// low) and dragging up (soft-tissue preset) pushes it away from the viewer: the crop the page
// sends has lo.y moved by the drag times the orbit-centre scale, nothing
// else moved, and the frame changes. `sentCrops`: every crop sent, in order.
async function checkCropDrag(page, sentCrops) {
  await page.selectOption('#render', 'dvr:ct-soft-tissue');  // the skin: cut into, it changes
  await page.click('#reset-view');
  await settled(page, '!h.interactive');
  const before3d = await canvasGrey(page);
  // The fields back to the volume's world box (their min and max).
  const box = await page.evaluate(() => {
    for (const k of ['x0', 'y0', 'z0']) document.getElementById(`crop-${k}`).value = document.getElementById(`crop-${k}`).min;
    for (const k of ['x1', 'y1', 'z1']) document.getElementById(`crop-${k}`).value = document.getElementById(`crop-${k}`).max;
    const get = (k) => Number(document.getElementById(`crop-${k}`).value);
    return { lo: ['x0', 'y0', 'z0'].map(get), hi: ['x1', 'y1', 'z1'].map(get) };
  });
  await page.check('input[name="tool"][value="crop"]');
  const r = await page.locator('#frame').boundingBox();
  const centre = [r.x + r.width / 2, r.y + r.height / 2];
  const dragCss = 160;  // ~155 mm: well into the abdomen (its skin lies ~80 mm inside the box)
  const sentBefore = sentCrops.length;
  await dragOnCanvas(page, centre, [centre[0], centre[1] - dragCss], 8);
  await page.mouse.up();
  await settled(page, '!h.interactive');
  const after3d = await canvasGrey(page);
  assert.ok(sentCrops.length > sentBefore, 'dragging a crop face sent no crop box');
  const crop = sentCrops[sentCrops.length - 1];
  const lo = [crop.lo_mm.x, crop.lo_mm.y, crop.lo_mm.z], hi = [crop.hi_mm.x, crop.hi_mm.y, crop.hi_mm.z];
  const { mm, framePx } = await page.evaluate((css) => {
    const canvas = document.getElementById('frame');
    const px = (css * canvas.width) / canvas.getBoundingClientRect().width;
    return { mm: window.vpmViewer.camera.mmPerPixel(canvas.width, canvas.height), framePx: px };
  }, dragCss);
  const want = box.lo[1] + framePx * mm;
  const cropDiff = meanAbsDiff(before3d, after3d);
  step(`Crop tool: dragged the anterior face ${dragCss} CSS px up: crop y0 ${box.lo[1].toFixed(1)} -> ` +
       `${lo[1].toFixed(1)} mm (expected ${want.toFixed(1)}), 3D mean |grey difference| ${cropDiff.toFixed(2)}`);
  assert.ok(Math.abs(lo[1] - want) <= 1.5 * mm + 0.1, `crop y0 ${lo[1]}, expected ${want}`);
  assert.ok(lo[1] > box.lo[1] + 10, 'the anterior face moved less than 10 mm');
  for (const [a, v] of [[0, lo[0]], [2, lo[2]]]) assert.ok(Math.abs(v - box.lo[a]) < 0.06, `lo[${a}] moved`);
  for (let a = 0; a < 3; ++a) assert.ok(Math.abs(hi[a] - box.hi[a]) < 0.06, `hi[${a}] moved`);
  assert.ok(cropDiff > kMinOrbitDiff, `the dragged crop face did not change the frame (${cropDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_crop_drag.png') });
  await page.check('input[name="tool"][value="orbit"]');
  await page.uncheck('#crop');
  await page.dispatchEvent('#crop', 'change');
  await settled(page, '!h.interactive');
}

// The case's row in the Cases panel (its cells' text), or null.
const caseRow = (page, caseId) => page.evaluate((id) => {
  const tr = document.querySelector(`#cases-body tr[data-case-id="${id}"]`);
  return tr && { current: tr.dataset.current === 'true',
                 cells: [...tr.cells].map((td) => td.textContent) };
}, caseId);

// The status line's case part after an undo or redo: [events, undone].
async function statusCounts(page) {
  const m = / · (\d+) events in effect, (\d+) undone/.exec(await page.textContent('#status'));
  return m && [Number(m[1]), Number(m[2])];
}

const framesReceived = (page) => page.evaluate(() => window.vpmViewer.framesReceived);

// Waits for a still frame received after the page's `framesBefore`th (the
// one the server sends after an undo, a redo, an open) showing `mm` as the
// largest displacement; returns its header.
function frameShowing(page, framesBefore, mm) {
  return settled(page, `!h.interactive && v.framesReceived > ${framesBefore} && ` +
                 `Math.abs(h.max_displacement_mm - ${mm}) < ${kReplayToleranceMm}`, 30000);
}

// A kept drag, then Ctrl+Z and Ctrl+Shift+Z. Returns {caseId, keptMm,
// view}: the case, its largest displacement with the drag (mm) and its view
// ([the Render select's value, crop on]) as the page set it.
async function checkUndoRedo(page, centre) {
  await page.check('#keep-drag');
  await page.check('input[name="tool"][value="grab"]');
  await dragOnCanvas(page, centre, [centre[0] - 25, centre[1] + 20], 10);
  await page.mouse.up();
  const kept = await settled(page, '!h.interactive && h.max_displacement_mm > 0', 60000);
  await page.uncheck('#keep-drag');
  const keptGrey = await canvasGrey(page);
  const caseId = await page.evaluate(() => window.vpmViewer.caseId);
  assert.match(caseId ?? '', /^case-[0-9a-f]+$/, 'the session has no case');
  const listed = (await refreshCases(page)).cases.find((c) => c.case_id === caseId);
  assert.ok(listed && listed.events > 0, `the case is not listed: ${JSON.stringify(listed)}`);

  let frames = await framesReceived(page);
  const undo = await pressUndoKeys(page, 'Control+z');
  await frameShowing(page, frames, undo.max_displacement_mm);
  const undoneGrey = await canvasGrey(page);
  const undoDiff = meanAbsDiff(keptGrey, undoneGrey);
  step(`Ctrl+Z: events ${listed.events} -> ${undo.events} (${undo.undone} undone), largest ` +
       `displacement ${kept.max_displacement_mm.toFixed(3)} -> ${undo.max_displacement_mm.toFixed(3)} ` +
       `mm, mean |grey difference| ${undoDiff.toFixed(2)}; status: ${await page.textContent('#status')}`);
  assert.ok(undo.changed && undo.events < listed.events && undo.undone > 0, JSON.stringify(undo));
  assert.ok(undo.max_displacement_mm < kept.max_displacement_mm - 0.5, 'the undo left the drag');
  assert.deepEqual(await statusCounts(page), [undo.events, undo.undone]);
  assert.ok(undoDiff > kMinGrabDiff, `the undo did not change the frame (${undoDiff})`);

  frames = await framesReceived(page);
  const redo = await pressUndoKeys(page, 'Control+Shift+KeyZ');
  await frameShowing(page, frames, redo.max_displacement_mm);
  const redoDiff = meanAbsDiff(keptGrey, await canvasGrey(page));
  step(`Ctrl+Shift+Z: events ${redo.events} (${redo.undone} undone), largest displacement ` +
       `${redo.max_displacement_mm.toFixed(4)} mm (kept drag ${kept.max_displacement_mm.toFixed(4)}, ` +
       `|difference| ${Math.abs(redo.max_displacement_mm - kept.max_displacement_mm).toExponential(1)}), ` +
       `mean |grey difference| to the kept drag's frame ${redoDiff.toFixed(2)}`);
  assert.ok(redo.changed && redo.redo, JSON.stringify(redo));
  assert.deepEqual([redo.events, redo.undone], [listed.events, 0]);
  assert.ok(Math.abs(redo.max_displacement_mm - kept.max_displacement_mm) < kReplayToleranceMm,
            `redo: ${redo.max_displacement_mm} mm, the kept drag ${kept.max_displacement_mm} mm`);
  assert.deepEqual(await statusCounts(page), [listed.events, 0]);
  assert.ok(redoDiff < 0.5 * undoDiff, `the redo did not bring the frame back (${redoDiff})`);
  figures.undo_mm = undo.max_displacement_mm;
  figures.redo_mm = redo.max_displacement_mm;
  await page.check('input[name="tool"][value="orbit"]');
  // The case's view, as the page's controls show it: what it keeps.
  const view = [await page.inputValue('#render'), await page.isChecked('#crop')];
  return { caseId, keptMm: redo.max_displacement_mm, view };
}

// The Cases panel after a refine (a new session: a new case): the kept
// case is listed closed with its displacement, renamed, opened again (its
// deformation replayed, its title in the status line, its kept view on the
// page's controls after the page showed another); the refined case is
// deleted (a dismissed confirm deletes nothing).
async function checkCases(page, kept) {
  const refinedCase = await page.evaluate(() => window.vpmViewer.caseId);
  assert.notEqual(refinedCase, kept.caseId);
  await page.click('#cases-toggle');  // the panel floats over the views
  let { cases } = await refreshCases(page);
  const row = await caseRow(page, kept.caseId);
  const listed = cases.find((c) => c.case_id === kept.caseId);
  step(`Cases panel: ${cases.length} cases; the kept one: ${row?.cells.join(' | ')}`);
  assert.ok(listed && row && !row.current, 'the kept case is not listed');
  assert.equal(row.cells[1], 'alice (you)');
  assert.equal(row.cells[5], 'closed');
  assert.ok(Math.abs(listed.max_displacement_mm - kept.keptMm) < kReplayToleranceMm,
            `listed ${listed.max_displacement_mm} mm, kept ${kept.keptMm} mm`);
  assert.equal(row.cells[4], `${kept.keptMm.toFixed(2)} mm`);
  assert.deepEqual((await caseRow(page, refinedCase))?.cells[5], 'open');
  assert.ok((await caseRow(page, refinedCase)).current, 'the case on screen is not marked');

  const title = 'Liver retraction, left lobe';
  page.once('dialog', (d) => d.accept(title));
  await page.click(`#cases-body tr[data-case-id="${kept.caseId}"] button:text("Rename")`);
  await page.waitForFunction(([id, t]) => window.vpmViewer.casesPanel.find(id)?.title === t,
                             [kept.caseId, title], { timeout: 15000 });
  assert.equal((await caseRow(page, kept.caseId)).cells[0], title);

  // The page shows another preset and crop meanwhile (on the refined case);
  // the kept case comes back with its own view on the controls.
  await page.selectOption('#render', kept.view[0] === 'dvr:ct-bone' ? 'dvr:ct-vessels' : 'dvr:ct-bone');
  await page.setChecked('#crop', !kept.view[1]);
  await settled(page, '!h.interactive');

  const frames = await framesReceived(page);
  await page.click(`#cases-body tr[data-case-id="${kept.caseId}"] button:text("Open")`);
  await page.waitForFunction((id) => window.vpmViewer.session?.case_id === id, kept.caseId,
                             { timeout: 60000 });
  const h = await frameShowing(page, frames, kept.keptMm);
  const shownView = [await page.inputValue('#render'), await page.isChecked('#crop')];
  step(`the kept case's view on the controls: render ${shownView[0]}, crop ${shownView[1]}`);
  assert.deepEqual(shownView, kept.view);
  assert.ok(await page.evaluate(() => window.vpmViewer.caseView !== null), 'no opened.view');
  const status = await page.textContent('#status');
  step(`opened ${kept.caseId} from the panel: largest displacement ` +
       `${h.max_displacement_mm.toFixed(4)} ` +
       `mm; status: ${status}`);
  assert.ok(status.includes(`case "${title}" (${kept.caseId})`), status);
  assert.ok((await caseRow(page, kept.caseId)).current);

  page.once('dialog', (d) => d.dismiss());
  await page.click(`#cases-body tr[data-case-id="${refinedCase}"] button:text("Delete")`);
  ({ cases } = await refreshCases(page));
  assert.ok(cases.some((c) => c.case_id === refinedCase), 'a dismissed confirm deleted the case');
  page.once('dialog', (d) => d.accept());
  await page.click(`#cases-body tr[data-case-id="${refinedCase}"] button:text("Delete")`);
  await page.waitForFunction((id) => !window.vpmViewer.casesPanel.find(id), refinedCase,
                             { timeout: 15000 });
  assert.equal(await caseRow(page, refinedCase), null);
  assert.equal(await page.evaluate(() => window.vpmViewer.caseId), kept.caseId);
  step(`renamed ${kept.caseId}, deleted ${refinedCase}`);
  await page.screenshot({ path: path.join(out, 'web_viewer_cases.png'), fullPage: true });
  await page.evaluate(() => window.scrollTo(0, 0));
}

// Alice's session is out of reach of a browser with no cookie and of Bob's,
// and so is her case.
async function checkIsolation(browser, url, aliceSession, aliceCase) {
  const anonymous = await browser.newContext();
  const a = await anonymous.newPage();
  const landed = await a.goto(url);
  assert.equal(new URL(a.url()).pathname, '/login', 'no cookie, yet not sent to sign in');
  assert.match(landed.headers()['content-security-policy'] ?? '', /frame-ancestors 'none'/);
  assert.ok(!(await a.content()).includes(aliceSession));
  const noCookie = await rawSocket(a, { type: 'watch', session_id: aliceSession });
  assert.ok(noCookie.refused, `a browser without a cookie opened the WebSocket: ${JSON.stringify(noCookie)}`);
  step('a second browser without a cookie: sent to /login, WebSocket refused');
  await anonymous.close();

  const bobs = await browser.newContext();
  const b = await bobs.newPage();
  await signInWithForm(b, url, bobToken);
  await b.waitForFunction(() => document.getElementById('user').textContent === 'bob');
  const watch = await rawSocket(b, { type: 'watch', session_id: aliceSession });
  assert.equal(watch.code, 'NOT_FOUND', JSON.stringify(watch));  // one answer for not yours and not there
  step(`bob's browser asks to watch alice's ${aliceSession}: ${watch.message}`);
  const sessions = await b.evaluate(() => fetch('/whoami').then((r) => r.json()));
  assert.deepEqual(sessions, { user: 'bob' });
  // Alice's cases: not in bob's list, and not his to open.
  const list = await rawSocket(b, { type: 'cases' }, ['cases', 'error']);
  assert.equal(list.type, 'cases', JSON.stringify(list));
  assert.ok(list.kept && !list.cases.some((c) => c.owner === 'alice'), JSON.stringify(list));
  const open = await rawSocket(b, { type: 'open_case', case_id: aliceCase });
  assert.deepEqual([open.code, open.case_id], ['NOT_FOUND', aliceCase], JSON.stringify(open));
  step(`bob's case list has none of alice's; opening her ${aliceCase}: ${open.message}`);
  await bobs.close();
}

async function main() {
  // Alice and Bob are users of both the server and the gateway.
  const usersFile = writeUsersFile(path.join(out, 'users.txt'), { alice: aliceToken, bob: bobToken });
  const stateDir = freshStateDir(out, 'viewer-state');
  const server = await startServer({ build, out, token, stateDir, args: ['--users', usersFile] });
  const gateway = await startGateway({ source, out, serverAddress: server.address, token,
                                       args: ['--users', usersFile] });
  step(`vpm-server ${server.address}, gateway ${gateway.url}`);

  const browser = await launchBrowser(source);
  // bypassCSP: the tests' waitForFunction predicates are strings, which the
  // page's Content-Security-Policy (no eval) would refuse; the page itself
  // runs under it in checkIsolation's browsers.
  const page = await browser.newPage({ viewport: { width: 1000, height: 900 }, bypassCSP: true });
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  const console_ = fs.createWriteStream(path.join(out, 'browser_console.log'));
  page.on('console', (m) => console_.write(`${m.type()}: ${m.text()}\n`));
  // Everything the gateway sends the browser, to check the token stays out.
  let tokenSeen = false;
  page.on('websocket', (ws) => ws.on('framereceived', ({ payload }) => {
    if (String(payload).includes(aliceToken)) tokenSeen = true;
  }));
  // Every crop box the page sends (settings events), for the Crop tool check.
  const sentCrops = [];
  const sentClips = [];  // the clip planes of every settings event
  page.on('websocket', (ws) => ws.on('framesent', ({ payload }) => {
    try {
      const settings = JSON.parse(String(payload))?.event?.settings;
      if (settings?.crop) sentCrops.push(settings.crop);
      if (settings) sentClips.push(settings.clip ?? []);
    } catch { /* not JSON: not a settings event */ }
  }));

  const t0 = performance.now();
  // A browser without a cookie lands on the sign-in form; Alice signs in.
  await signInWithForm(page, gateway.url, aliceToken);
  await page.waitForFunction(() => document.getElementById('user').textContent === 'alice');
  const cookies = await page.context().cookies();
  assert.equal(cookies.length, 1);
  assert.ok(cookies[0].httpOnly && cookies[0].sameSite === 'Strict', JSON.stringify(cookies));
  step('signed in as alice through the form (HttpOnly, SameSite=Strict cookie)');
  await page.waitForSelector('#server-state[data-state="up"]', { timeout: 15000 });
  step('page loaded, gateway reports vpm-server up');

  await page.selectOption('#volume', 'source:phantom:abdomen?size=128');
  await page.selectOption('#frame-size', '256');
  const tOpen = performance.now();
  await page.click('#open');
  await settled(page, '!h.interactive', 120000);
  figures.first_frame_ms = Math.round(performance.now() - tOpen);
  const first = await canvasGrey(page);
  step(`first frame after ${figures.first_frame_ms} ms: mean ${first.mean.toFixed(1)}, ` +
       `variance ${first.variance.toFixed(1)}`);
  assert.ok(first.variance > kMinVariance,
            `the first frame looks blank: grey variance ${first.variance} <= ${kMinVariance}`);
  // Frame 256: the frame's longer side, in the 3D pane's shape.
  assert.equal(await page.evaluate(() => {
    const c = document.getElementById('frame');
    return Math.max(c.width, c.height);
  }), 256);

  const box = await page.locator('#frame').boundingBox();
  const centre = [box.x + box.width / 2, box.y + box.height / 2];

  // Orbit: 200 CSS pixels = 100 frame pixels at 0.4 degree each, 40 degrees.
  await dragOnCanvas(page, centre, [centre[0] + 200, centre[1]], 10);
  await page.mouse.up();
  await settled(page, '!h.interactive');
  const orbited = await canvasGrey(page);
  const orbitDiff = meanAbsDiff(first, orbited);
  step(`orbit drag: mean |grey difference| ${orbitDiff.toFixed(2)}`);
  assert.ok(orbitDiff > kMinOrbitDiff, `the orbit drag did not change the frame (${orbitDiff})`);

  // The vessels preset: soft tissue clears, so a deformation inside shows.
  await page.selectOption('#render', 'dvr:ct-vessels');
  await settled(page, '!h.interactive');
  const before = await canvasGrey(page);
  const presetDiff = meanAbsDiff(orbited, before);
  step(`preset ct-vessels: mean |grey difference| ${presetDiff.toFixed(2)}`);
  assert.ok(presetDiff > kMinOrbitDiff, `the preset did not change the frame (${presetDiff})`);

  // Grab the tissue under the centre and drag it; hold still until the
  // still frame arrives, so the comparison is between two still frames.
  await page.check('input[name="tool"][value="grab"]');
  const tGrab = performance.now();
  await dragOnCanvas(page, centre, [centre[0] + 20, centre[1] - 30], 12);
  const held = await settled(page, '!h.interactive && h.max_displacement_mm > 0', 60000);
  figures.grab_to_still_ms = Math.round(performance.now() - tGrab);
  figures.max_displacement_mm = held.max_displacement_mm;
  const dragged = await canvasGrey(page);
  const grabDiff = meanAbsDiff(before, dragged);
  step(`grab and drag: server max_displacement_mm ${held.max_displacement_mm.toFixed(2)}, ` +
       `mean |grey difference| ${grabDiff.toFixed(2)}`);
  assert.ok(grabDiff > kMinGrabDiff, `the grab-and-drag did not change the frame (${grabDiff})`);
  const peak = await page.evaluate(() => window.vpmViewer.peakDisplacementMm);
  assert.ok(peak > 0, 'the page never saw a deformation');
  const statusLine = await page.textContent('#status');
  step(`status line: ${statusLine}`);
  assert.match(statusLine, /\d+ fps · latency \d+ ms · \d+x\d+ [\d.]+ KB jpeg/);
  const shown = /max displacement ([\d.]+) mm/.exec(statusLine);
  assert.ok(shown && Number(shown[1]) > 0, 'the status line shows no displacement');
  const shot = path.join(out, 'web_viewer_drag.png');
  await page.screenshot({ path: shot });
  step(`screenshot ${shot}`);

  // The mesh overlay while holding (the mouse is busy: the keyboard
  // toggles it): vertices, handles and the drag arrow.
  await page.focus('#overlay');
  await page.keyboard.press('Space');
  await settled(page, '!h.interactive');
  const overlaid = await canvasGrey(page);
  const overlayDiff = meanAbsDiff(dragged, overlaid);
  step(`overlay on: mean |grey difference| ${overlayDiff.toFixed(2)}`);
  assert.ok(overlayDiff > kMinGrabDiff, `the overlay did not change the frame (${overlayDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_drag_overlay.png') });
  await page.keyboard.press('Space');
  await settled(page, '!h.interactive');

  await page.mouse.up();
  await settled(page, '!h.interactive');
  const released = await canvasGrey(page);
  const releaseDiff = meanAbsDiff(before, released);
  step(`release: mean |grey difference| to before the grab ${releaseDiff.toFixed(2)}`);
  assert.ok(releaseDiff < 0.5 * grabDiff, 'release did not bring the tissue back to rest');
  await page.screenshot({ path: path.join(out, 'web_viewer_released.png') });

  // A sustained drag (a circle of 30 mm radius on screen, 2 s): measured,
  // not asserted beyond "frames kept coming", since the machine's load
  // sets the rate.
  const framesAtStart = await page.evaluate(() => window.vpmViewer.framesReceived);
  const latencies = [];
  await page.mouse.move(centre[0], centre[1]);
  await page.mouse.down();
  const tSustained = performance.now();
  for (let i = 1; performance.now() - tSustained < 2000; ++i) {
    const a = (i / 20) * 2 * Math.PI;
    await page.mouse.move(centre[0] + 30 * Math.sin(a), centre[1] - 30 * (1 - Math.cos(a)));
    await page.waitForTimeout(25);
    latencies.push(await page.evaluate(() => window.vpmViewer.stats.latencyMs));
  }
  const sustainedS = (performance.now() - tSustained) / 1000;
  const sustainedFrames = (await page.evaluate(() => window.vpmViewer.framesReceived)) -
    framesAtStart;
  await page.mouse.up();
  await settled(page, '!h.interactive');
  const uniqueLatencies = [...new Set(latencies.filter((v) => v !== null))].sort((a, b) => a - b);
  figures.drag_fps = Number((sustainedFrames / sustainedS).toFixed(1));
  figures.drag_latency_median_ms = Math.round(
    uniqueLatencies[Math.floor(uniqueLatencies.length / 2)] ?? NaN);
  step(`sustained drag: ${sustainedFrames} frames in ${sustainedS.toFixed(1)} s ` +
       `(${figures.drag_fps} fps), median event-to-frame latency ` +
       `${figures.drag_latency_median_ms} ms`);
  assert.ok(sustainedFrames >= 1, 'no frame arrived during a sustained drag');
  // Released (not kept), the tissue returns to the grab point, and the
  // slices go through it, whatever frames of the drag were still on their
  // way (each moved the planes to where the pointer then was).
  const planes = await page.evaluate(() => ({ at: window.vpmViewer.slices.at,
                                              grab: window.vpmViewer.lastGrabMm }));
  step(`slices after the release: ${JSON.stringify(planes.at)}, grab point ` +
       `${JSON.stringify(planes.grab)}`);
  for (const [view, axis] of [['axial', 'z'], ['coronal', 'y'], ['sagittal', 'x']]) {
    assert.ok(Math.abs(planes.at[view] - planes.grab[axis]) < 0.5,
              `the ${view} slice is not through the released grab's point`);
  }
  const kept = await checkUndoRedo(page, centre);

  // Refine at the grabbed point: a new mesh with refined vertices, a new
  // session on it, frames again.
  const oldSession = await page.evaluate(() => window.vpmViewer.session.session_id);
  await page.click('#refine-grab');
  await page.waitForFunction((old) => window.vpmViewer.session?.session_id !== old &&
                             window.vpmViewer.mesh.stats.refined > 0, oldSession,
                             { timeout: 60000 });
  await settled(page, `!h.interactive && v.framesReceived > ${await page.evaluate(
    () => window.vpmViewer.framesReceived)}`);
  const refined = await page.evaluate(() => window.vpmViewer.mesh.stats);
  step(`refine at the grab: ${refined.vertices} vertices, ${refined.refined} refined`);
  assert.match(await page.textContent('#mesh-info'), new RegExp(`${refined.refined} refined`));

  // Wheel zoom and MIP each change the frame.
  const unzoomed = await canvasGrey(page);
  await page.mouse.move(centre[0], centre[1]);
  await page.mouse.wheel(0, -400);
  await settled(page, '!h.interactive');
  const zoomDiff = meanAbsDiff(unzoomed, await canvasGrey(page));
  step(`wheel zoom: mean |grey difference| ${zoomDiff.toFixed(2)}`);
  assert.ok(zoomDiff > kMinOrbitDiff, `the wheel did not zoom (${zoomDiff})`);
  const dvr = await canvasGrey(page);
  await page.selectOption('#render', 'mip:ct-vessels');
  await settled(page, '!h.interactive');
  const mipDiff = meanAbsDiff(dvr, await canvasGrey(page));
  step(`MIP: mean |grey difference| ${mipDiff.toFixed(2)}`);
  assert.ok(mipDiff > kMinOrbitDiff, `MIP did not change the frame (${mipDiff})`);
  await page.screenshot({ path: path.join(out, 'web_viewer_mip.png') });
  await page.selectOption('#render', 'dvr:ct-vessels');
  await checkSlicesAndCuts(page, sentClips);
  await checkCropDrag(page, sentCrops);

  figures.latency_ms = await page.evaluate(() => window.vpmViewer.stats.latencyMs);
  assert.ok(!tokenSeen, 'the token reached the browser');
  assert.ok(!(await page.content()).includes(aliceToken), 'the token is in the page');
  assert.ok(!(await page.evaluate(() => document.cookie)).includes('vpm_session'),
            'the page script can read the sign-in cookie');

  await checkIsolation(browser, gateway.url,
                       ...await page.evaluate(() => [window.vpmViewer.session.session_id,
                                                     window.vpmViewer.caseId]));
  await checkCases(page, kept);
  assert.deepEqual(pageErrors, [], 'the page threw');

  // The server goes away: the page says so.
  await stopChild(server.child);
  await page.waitForSelector('#message[data-kind="error"]', { timeout: 15000 });
  const downMessage = await page.textContent('#message');
  step(`server stopped; the page says: ${downMessage}`);
  assert.match(downMessage, /vpm-server at 127\.0\.0\.1:\d+ is not reachable/);
  assert.equal(await page.getAttribute('#server-state', 'data-state'), 'down');

  // It comes back on the same port and state dir with nothing loaded: the
  // session is gone (NOT_FOUND), and the page reopens its case by itself.
  const framesBefore = await page.evaluate(() => window.vpmViewer.framesReceived);
  const tRestart = performance.now();
  await startServer({ build, out, token, port: server.port, logName: 'server_restarted.log',
                     stateDir, args: ['--users', usersFile] });
  await page.waitForFunction((n) => window.vpmViewer.framesReceived > n, framesBefore,
                             { timeout: 60000, polling: 100 });
  await settled(page, '!h.interactive', 60000);
  figures.recovered_after_restart_ms = Math.round(performance.now() - tRestart);
  const reopened = await page.evaluate(() => window.vpmViewer.volume.source);
  step(`server restarted: the page reopened ${reopened} and shows frames after ` +
       `${figures.recovered_after_restart_ms} ms`);
  assert.equal(reopened, 'phantom:abdomen?size=128');
  const back = await settled(page, '!h.interactive && ' +
    `Math.abs(h.max_displacement_mm - ${kept.keptMm}) < ${kReplayToleranceMm}`, 30000);
  const backCase = await page.evaluate(() => window.vpmViewer.session.case_id);
  step(`the page is back in ${backCase} (was ${kept.caseId}): largest displacement ` +
       `${back.max_displacement_mm.toFixed(4)} mm (before ${kept.keptMm.toFixed(4)}, |difference| ` +
       `${Math.abs(back.max_displacement_mm - kept.keptMm).toExponential(1)} mm)`);
  assert.equal(backCase, kept.caseId);
  await page.screenshot({ path: path.join(out, 'web_viewer_recovered.png') });
  assert.equal(await page.getAttribute('#server-state', 'data-state'), 'up');

  figures.total_ms = Math.round(performance.now() - t0);
  fs.writeFileSync(path.join(out, 'viewer_e2e.json'), JSON.stringify(figures, null, 2));
  step(`figures ${JSON.stringify(figures)}`);
  await browser.close();
}

runScenario('web_e2e', main);

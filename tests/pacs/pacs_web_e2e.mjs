// The browser half of pacs_web_e2e.py: the Studies panel and Export to PACS
// in headless Chromium, through the gateway, on the vpm-server and Orthanc
// that the Python driver started (tests/pacs/pacs_harness.py).
//
// As alice: sign in, search by patient-name wildcard (the study row shows
// name, ID, birth date, study date, modalities, series count), list the
// study's series (the CT of 112 images and the SR), open the SR (the
// server's "holds no images" in the panel), open the CT (frames in the 3D
// view), grab the left kidney by its pixel and drag it 20 mm superior with
// "Keep drags" on (the frame reports more than 5 mm), Export to PACS
// (window.vpmViewer.lastExport). As bob, in a second browser context: the
// panel says he has no endpoint, and the gateway refuses his search and his
// open of alice's series. Writes RESULT (JSON: the export's summary) for the
// driver, which checks Orthanc and the logs.
//
// Usage: node pacs_web_e2e.mjs --source SOURCE --config CONFIG.json --result RESULT.json
// CONFIG: {server, users_file, tokens: {alice, bob}, study_uid, ct_series_uid,
//          sr_series_uid, patient: {name, id, birth_date, study_date},
//          kidney_lps_mm: [x, y, z]}. Logs and, on failure, screenshots go
// next to CONFIG.
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { parseArgs } from 'node:util';

const { values: args } = parseArgs({
  options: { source: { type: 'string' }, config: { type: 'string' }, result: { type: 'string' } },
});
const source = path.resolve(args.source);
const config = JSON.parse(fs.readFileSync(args.config, 'utf8'));
const out = path.dirname(path.resolve(args.config));
const { canvasGrey, launchBrowser, runScenario, settled, signInWithForm, startGateway, stopAll } =
  await import(path.join(source, 'tests', 'web', 'harness.mjs'));

const kMinVariance = 50;          // grey variance of a frame that is not blank
const kMinDisplacementMm = 5;     // what the drag must move the tissue by
const kDragMm = 20;               // the pointer's travel on the orbit-centre plane
const step = (text) => console.log(`pacs_web_e2e: ${text}`);
const pages = {};                 // name -> page, for the failure report

// Waits for `predicate` (a function of `arg` run in the page) for at most
// timeoutMs; on timeout the error says what was awaited.
async function waitFor(page, what, predicate, arg, timeoutMs) {
  try {
    await page.waitForFunction(predicate, arg, { timeout: timeoutMs, polling: 100 });
  } catch (e) {
    throw new Error(`${what}: not within ${timeoutMs} ms (${e.message.split('\n')[0]})`);
  }
}

const panelState = (page) => page.evaluate(() => ({
  state: document.getElementById('studies').dataset.state,
  note: document.getElementById('pacs-note').textContent,
}));

// Cells of the rows matching `selector`, as text.
const rowCells = (page, selector) =>
  page.$$eval(`${selector} td:not(.thumb)`, (tds) => tds.map((td) => td.textContent.trim()));

// What each page showed, printed and saved as a screenshot in `out`.
async function reportPages() {
  for (const [name, page] of Object.entries(pages)) {
    try {
      const shown = await page.evaluate(() => {
        const text = (id) => document.getElementById(id)?.textContent ?? null;
        const v = window.vpmViewer ?? {};
        return { url: location.href, user: text('user'), server: text('server-state'),
                 studies: document.getElementById('studies')?.dataset.state, note: text('pacs-note'),
                 message: text('message'), status: text('status'), errors: v.errors,
                 source: v.volume?.source, header: v.lastHeader, lastExport: v.lastExport };
      });
      console.error(`pacs_web_e2e: ${name}'s page showed: ${JSON.stringify(shown)}`);
      const shot = path.join(out, `failure_${name}.png`);
      await page.screenshot({ path: shot, timeout: 10000 });
      console.error(`pacs_web_e2e: screenshot ${shot}`);
    } catch (e) {
      console.error(`pacs_web_e2e: no report of ${name}'s page: ${e.message}`);
    }
  }
}

// Opens a WebSocket to the gateway from `page` (its cookie, its origin),
// sends `message` and resolves with the first reply of a type in `types`.
function rawSocket(page, message, types) {
  return page.evaluate(([m, wanted]) => new Promise((resolve) => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    ws.onopen = () => ws.send(JSON.stringify(m));
    ws.onmessage = (e) => {
      if (typeof e.data !== 'string') return;
      const r = JSON.parse(e.data);
      if (wanted.includes(r.type)) {
        resolve(r);
        ws.close();
      }
    };
    ws.onclose = () => resolve({ closed: true });
    setTimeout(() => resolve({ timeout: true }), 15000);
  }), [message, types]);
}

async function searchAndList(page) {
  const { patient } = config;
  await page.click('#studies-toggle');
  await waitFor(page, 'the endpoint list', () =>
    [...document.getElementById('pacs-endpoint').options].some((o) => o.value === 'orthanc'),
  null, 15000);
  const [family, given] = patient.name.split('^');
  const wildcard = `${family}^${given.slice(0, 3)}*`;
  await page.fill('#pacs-patient-name', wildcard);
  await page.click('#pacs-search');
  await waitFor(page, 'the search', () =>
    document.getElementById('studies').dataset.state !== 'searching', null, 30000);
  const row = `#pacs-studies-body tr[data-study-uid="${config.study_uid}"]`;
  assert.ok(await page.locator(row).count() === 1,
            `the study is not listed: ${JSON.stringify(await panelState(page))}`);
  const cells = await rowCells(page, row);
  step(`search "${wildcard}": ${await page.textContent('#pacs-note')}`);
  const isoDate = (d) => `${d.slice(0, 4)}-${d.slice(4, 6)}-${d.slice(6)}`;
  assert.equal(await page.locator('#pacs-studies-body tr').count(), 1, 'one study matches');
  assert.deepEqual([cells[0], cells[1], cells[2], cells[3], cells[6]],
                   [`${family}, ${given}`, patient.id, isoDate(patient.birth_date),
                    isoDate(patient.study_date), '3'], `the study row: ${JSON.stringify(cells)}`);
  assert.deepEqual(cells[5].split(' ').sort(), ['CT', 'SR'], `modalities: ${cells[5]}`);
  step('the study row shows the patient name, ID, birth date, study date, CT SR, 3 series');

  await page.click(row);
  const ctRow = `#pacs-series-body tr[data-series-uid="${config.ct_series_uid}"][data-modality="CT"]`;
  const srRow = `#pacs-series-body tr[data-series-uid="${config.sr_series_uid}"][data-modality="SR"]`;
  await page.waitForSelector(ctRow, { timeout: 30000 });
  await page.waitForSelector(srRow, { timeout: 5000 });
  const ct = await rowCells(page, ctRow);
  const sr = await rowCells(page, srRow);
  assert.deepEqual([ct[0], ct[1], ct[2], ct[4]], ['2', 'CT', 'Abdomen 3mm', '112'],
                   `the CT row: ${JSON.stringify(ct)}`);
  assert.deepEqual([sr[0], sr[1]], ['9', 'SR'], `the SR row: ${JSON.stringify(sr)}`);
  step(`series: CT ${JSON.stringify(ct.slice(0, 5))}, SR ${JSON.stringify(sr.slice(0, 5))}`);

  // The CT's thumbnail is shown (rendered by vpm-server from one instance
  // Orthanc sent); the SR's row says it has none.
  await waitFor(page, 'the CT thumbnail', (sel) => {
    const img = document.querySelector(`${sel} img.pacs-thumb`);
    return img?.dataset.state === 'shown' && img.complete && img.naturalWidth > 0;
  }, ctRow, 30000);
  const thumb = await page.$eval(`${ctRow} img.pacs-thumb`,
                                 (img) => [img.naturalWidth, img.naturalHeight]);
  await waitFor(page, 'the SR row without thumbnail', (sel) =>
    document.querySelector(`${sel} img.pacs-thumb`)?.dataset.state === 'none', srRow, 30000);
  step(`the CT row's thumbnail: ${thumb[0]} x ${thumb[1]} pixels; the SR row has none`);
  await page.screenshot({ path: path.join(out, 'studies.png') });

  // Alice may browse the data root: its Server files list the kidney series.
  const entry = `#server-files-body tr[data-name="${config.data_root_entry}"][data-kind="DICOM_FOLDER"]`;
  await page.waitForSelector(entry, { timeout: 15000 });
  assert.equal(await page.locator(`${entry} button.server-open`).count(), 1);
  step(`alice's Server files: ${await page.textContent('#server-files-note')} ` +
       `(${config.data_root_entry}: a DICOM series)`);

  await page.click(`${srRow} button.pacs-open`);
  await waitFor(page, 'the SR refused', () =>
    document.getElementById('studies').dataset.state === 'error', null, 60000);
  const refused = await panelState(page);
  assert.match(refused.note, /holds no images/, JSON.stringify(refused));
  step(`opening the SR: ${refused.note}`);
  return ctRow;
}

// The frame pixel showing the world point `lps` (mm), the canvas's CSS box
// and the millimetres per frame pixel on the plane where picks land.
function pixelOf(page, lps) {
  return page.evaluate((w) => {
    const c = window.vpmViewer.camera;
    const canvas = document.getElementById('frame');
    const rel = [0, 1, 2].map((a) => w[a] - c.originLps[a]);
    const physical = c.columns.map((col) => col[0] * rel[0] + col[1] * rel[1] + col[2] * rel[2]);
    const px = c.projectToPixel(physical, canvas.width, canvas.height);
    const picked = px && c.pickPointMm(px[0], px[1], canvas.width, canvas.height);
    const r = canvas.getBoundingClientRect();
    return { px, inside: Boolean(picked) && c.insideVolume(picked), left: r.left, top: r.top,
             cssPerPixel: r.width / canvas.width,
             mmPerPixel: c.mmPerPixel(canvas.width, canvas.height) };
  }, lps);
}

async function openAndDrag(page, ctRow) {
  await page.click(`${ctRow} button.pacs-open`);
  await waitFor(page, 'the CT opened', () => ['opened', 'error'].includes(
    document.getElementById('studies').dataset.state), null, 90000);
  const opened = await panelState(page);
  assert.equal(opened.state, 'opened', JSON.stringify(opened));
  const header = await settled(page, '!h.interactive && v.framesDrawn > 0', 60000);
  const first = await canvasGrey(page);
  const source = await page.evaluate(() => window.vpmViewer.volume.source);
  assert.equal(source, `pacs:orthanc/${config.study_uid}/${config.ct_series_uid}`);
  assert.ok(first.variance > kMinVariance, `the first frame looks blank (${first.variance})`);
  step(`opened ${source}: ${header.width}x${header.height} frame, grey variance ` +
       `${first.variance.toFixed(0)}; ${opened.note}`);

  await page.click('#studies-close');  // the panel floats over the right of the page
  await page.check('#keep-drag');
  await page.check('input[name="tool"][value="grab"]');
  const at = await pixelOf(page, config.kidney_lps_mm);
  assert.ok(at.px && at.inside, `the kidney's pixel picks outside the volume: ${JSON.stringify(at)}`);
  const css = (px) => [at.left + px[0] * at.cssPerPixel, at.top + px[1] * at.cssPerPixel];
  const from = css(at.px);
  const to = css([at.px[0], at.px[1] - kDragMm / at.mmPerPixel]);  // screen up: superior
  await page.mouse.move(from[0], from[1]);
  await page.mouse.down();
  await page.mouse.move(to[0], to[1], { steps: 12 });
  await settled(page, `!h.interactive && h.max_displacement_mm > ${kMinDisplacementMm}`, 60000);
  await page.mouse.up();  // "Keep drags": the tissue stays where it was dragged
  const kept = await settled(page, `!h.interactive && h.max_displacement_mm > ${kMinDisplacementMm}`,
                             60000);
  // The server picks where the pixel's ray meets the plane through the
  // orbit centre facing the camera: the point it grabbed (the frame's
  // grab_point_mm) is on the kidney's line of sight, so it shows at the
  // kidney's pixel.
  const grab = await page.evaluate(() => window.vpmViewer.lastGrabMm);
  assert.ok(grab, 'no grab point in the frames');
  const seen = await pixelOf(page, [grab.x, grab.y, grab.z]);
  assert.ok(Math.hypot(seen.px[0] - at.px[0], seen.px[1] - at.px[1]) < 1.5,
            `the grab at ${JSON.stringify(grab)} shows at pixel ${seen.px}, the kidney at ${at.px}`);
  const status = await page.textContent('#status');
  const shown = /max displacement ([\d.]+) mm/.exec(status);
  assert.ok(shown && Number(shown[1]) > kMinDisplacementMm, `status line: ${status}`);
  step(`grabbed the kidney at frame pixel (${at.px.map((v) => v.toFixed(0))}), LPS ` +
       `(${[grab.x, grab.y, grab.z].map((v) => v.toFixed(1))}) mm, dragged ` +
       `${kDragMm} mm superior and kept: max displacement ${kept.max_displacement_mm.toFixed(2)} mm`);
  await page.screenshot({ path: path.join(out, 'dragged.png') });
  return source;
}

async function exportToPacs(page) {
  const label = await page.textContent('#export-pacs');
  assert.equal(label, 'Export to PACS (orthanc)');
  assert.ok(await page.isEnabled('#export-pacs'), 'Export to PACS is disabled');
  await page.click('#export-pacs');
  await waitFor(page, 'the export', () => window.vpmViewer.lastExport !== null ||
    window.vpmViewer.errors.some((e) => e.what === 'PACS export'), null, 120000);
  const { summary, errors } = await page.evaluate(() => ({
    summary: window.vpmViewer.lastExport, errors: window.vpmViewer.errors }));
  assert.ok(summary, `the export failed: ${JSON.stringify(errors)}`);
  const message = await page.textContent('#message');
  assert.match(message, /^Sent 113 instances of series [\d.]+ to orthanc, study [\d.]+\.$/, message);
  assert.equal(summary.study_uid, config.study_uid);
  assert.equal(summary.instances, 113);
  assert.ok(summary.max_displacement_mm > kMinDisplacementMm, JSON.stringify(summary));
  step(`Export to PACS: ${message} (largest displacement ${summary.max_displacement_mm.toFixed(2)} mm)`);
  return summary;
}

// The series of two echoes opens on echo 1; the Stack picker names both and
// opens echo 2 (pacs:...?stack=2), whose values are echo 1's + echo_offset.
async function pickStack(page) {
  await page.click('#studies-toggle');
  const echoRow = `#pacs-series-body tr[data-series-uid="${config.echo_series_uid}"]`;
  await page.waitForSelector(echoRow, { timeout: 15000 });
  await page.click(`${echoRow} button.pacs-open`);
  const base = `pacs:orthanc/${config.study_uid}/${config.echo_series_uid}`;
  const opened = (src) => waitFor(page, `${src} opened`, (s) =>
    window.vpmViewer.volume?.source === s && window.vpmViewer.session &&
    !document.getElementById('stack-pick').hidden, src, 90000);
  await opened(base);
  const first = await page.evaluate(() => ({
    options: [...document.getElementById('stack').options].map((o) => o.textContent),
    value: document.getElementById('stack').value, volume: window.vpmViewer.volume }));
  assert.deepEqual(first.options, ['1: EchoNumbers 1', '2: EchoNumbers 2'], JSON.stringify(first));
  assert.equal(first.value, '1');
  assert.equal(first.volume.stack, 1);
  step(`opened ${base}: Stack picker ${JSON.stringify(first.options)}, showing 1`);
  await page.click('#studies-close');
  await page.selectOption('#stack', '2');
  await opened(`${base}?stack=2`);
  const second = await page.evaluate(() => ({
    value: document.getElementById('stack').value, volume: window.vpmViewer.volume,
    message: document.getElementById('message').textContent }));
  assert.equal(second.value, '2');
  assert.equal(second.volume.stack, 2);
  assert.ok(Math.abs(second.volume.max_value - first.volume.max_value - config.echo_offset) < 0.01,
            `echo 2's largest value ${second.volume.max_value}, echo 1's ${first.volume.max_value}`);
  assert.match(second.message, /read stack 2 \(EchoNumbers 2/, second.message);
  // The Volume picker names the volume shown (Open reopens it).
  await waitFor(page, 'the Volume picker on the volume shown', () =>
    document.getElementById('volume').value === `volume:${window.vpmViewer.volume.volume_id}`,
  null, 15000);
  await settled(page, '!h.interactive && v.framesDrawn > 0', 60000);
  step(`picked stack 2: ${second.volume.source}, largest value ${second.volume.max_value} ` +
       `(echo 1: ${first.volume.max_value})`);
  await page.screenshot({ path: path.join(out, 'stack2.png') });
}

// Bob: the endpoints file lists only alice.
async function bobSeesNoEndpoint(browser, url, aliceSource) {
  const context = await browser.newContext({ viewport: { width: 1280, height: 800 }, bypassCSP: true });
  const page = (pages.bob = await context.newPage());
  await signInWithForm(page, url, config.tokens.bob);
  await waitFor(page, 'bob signed in', () =>
    document.getElementById('user').textContent === 'bob', null, 10000);
  await page.click('#studies-toggle');
  await waitFor(page, 'the panel\'s answer to bob', () =>
    /No PACS endpoint you may use/.test(document.getElementById('pacs-note').textContent), null, 15000);
  const note = await page.textContent('#pacs-note');
  assert.ok(await page.isDisabled('#pacs-search'), 'bob\'s Search is enabled');
  assert.ok(await page.isDisabled('#export-pacs'), 'bob\'s Export is enabled');
  step(`bob's Studies panel: ${note}`);
  await waitFor(page, 'bob\'s data root answer', () =>
    window.vpmViewer.errors.some((e) => e.what === 'Server files'), null, 15000);
  assert.ok(await page.isHidden('#server-files'), 'bob sees the Server files section');
  step('bob has no Server files section (no browse-data-root)');
  const search = await rawSocket(page, { type: 'pacs_search', endpoint: 'orthanc' },
                                 ['pacs_studies', 'pacs_error', 'error']);
  const open = await rawSocket(page, { type: 'pacs_open', source: aliceSource },
                               ['pacs_loaded', 'pacs_error', 'error']);
  assert.deepEqual([search.type, search.code], ['pacs_error', 'PERMISSION_DENIED'],
                   JSON.stringify(search));
  assert.deepEqual([open.type, open.code], ['pacs_error', 'PERMISSION_DENIED'], JSON.stringify(open));
  step(`bob's own search on orthanc and open of alice's series: ${open.code} (${open.message})`);
  await context.close();
  delete pages.bob;
}

async function main() {
  const gateway = await startGateway({ source, out, serverAddress: config.server, token: '',
                                       args: ['--users', config.users_file] });
  step(`gateway ${gateway.url} on vpm-server ${config.server}`);
  const browser = await launchBrowser(source);
  try {
    // bypassCSP: settled()'s predicates are strings, which the page's
    // Content-Security-Policy (no eval) would refuse.
    const context = await browser.newContext({ viewport: { width: 1280, height: 800 },
                                               bypassCSP: true });
    const page = (pages.alice = await context.newPage());
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(e.message));
    await signInWithForm(page, gateway.url, config.tokens.alice);
    await waitFor(page, 'alice signed in', () =>
      document.getElementById('user').textContent === 'alice', null, 10000);
    await page.waitForSelector('#server-state[data-state="up"]', { timeout: 15000 });
    await page.selectOption('#frame-size', '256');  // lavapipe on 2 cores
    step('alice signed in; vpm-server up');

    const ctRow = await searchAndList(page);
    const source = await openAndDrag(page, ctRow);
    const summary = await exportToPacs(page);
    await pickStack(page);
    await bobSeesNoEndpoint(browser, gateway.url, source);
    assert.deepEqual(pageErrors, [], 'script errors on alice\'s page');
    fs.writeFileSync(args.result, JSON.stringify({ summary, source }));
  } catch (e) {
    await reportPages();
    throw e;
  } finally {
    await browser.close();
  }
}

// Every wait above is bounded; this bounds their sum, with the report.
const kDeadlineMs = 180000;
setTimeout(async () => {
  console.error(`pacs_web_e2e: FAIL: not done in ${kDeadlineMs / 1000} s`);
  await reportPages();
  await stopAll();
  process.exit(1);
}, kDeadlineMs).unref();
runScenario('pacs_web_e2e', main);

// The page's uploads from the desktop (public/upload_panel.js) in headless
// Chromium, through the gateway to the stand-in server (fake_upload.mjs):
//  1. at 1280 x 800 the volume row stays one line, no wider than the
//     window, with Upload... and Folder..., and with the bar and Cancel that
//     take their place during an upload (the 3D view does not move);
//  2. a NIfTI picked with Upload... (its extension in upper case) reaches the
//     server as NAME.nii.gz and opens as a volume of the list does (frames);
//  3. a folder picked with Folder... arrives as FOLDER.zip that Python reads,
//     its hidden file left out; files dropped on the page show the overlay
//     and arrive as a ZIP; the notes the server's reader gives the volume
//     (here: which series of the folder) are on the message line;
//  4. a file over the gateway's cap is refused in the page, nothing sent; the
//     server's INVALID_ARGUMENT reaches the message line in words;
//  5. Cancel while the server reads cancels the server's call.
// Usage: node upload_page_e2e.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { startFakeServer } from './fake_vpm_server.mjs';
import { startGatewayProcess } from './gateway_client.mjs';
import { launchBrowser, runScenario, signInWithForm, testPaths, track } from './harness.mjs';
import { readZip } from './zip_check.mjs';

const { source, out } = testPaths(process.argv);
const step = (text) => console.log(`web_upload_page: ${text}`);
const kToken = crypto.randomBytes(16).toString('hex');
const kCapBytes = 4 * 1024 * 1024;

const stateIs = (page, states, timeout = 20000) => page.waitForFunction(
  (wanted) => wanted.includes(document.getElementById('upload').dataset.state), states,
  { timeout, polling: 50 });
const layout = (page) => page.evaluate(() => ({
  frameTop: document.getElementById('frame').getBoundingClientRect().top,
  rowHeight: document.getElementById('picker').getBoundingClientRect().height,
  pageWidth: document.documentElement.scrollWidth,
}));

async function main() {
  const files = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-web-upload-page-'));
  const fake = await startFakeServer(source);
  const users = path.join(files, 'users.txt');
  fs.writeFileSync(users, `alice ${crypto.createHash('sha256').update(kToken).digest('hex')}\n`);
  const { child, base } = await startGatewayProcess({
    source, stderr: fs.openSync(path.join(out, 'upload_page_gateway.log'), 'w'),
    args: ['--server', fake.address, '--users', users, '--max-upload-bytes', String(kCapBytes)] });
  track(child);
  const browser = await launchBrowser(source);
  try {
    const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
    await signInWithForm(page, `${base}/`, kToken);
    await page.waitForFunction(() => window.vpmViewer?.uploads?.tabId);
    const idle = await layout(page);
    assert.ok(idle.rowHeight < 40, `the volume row wraps: ${idle.rowHeight} px`);
    assert.ok(idle.pageWidth <= 1280, `the page is ${idle.pageWidth} px wide`);

    step('a NIfTI through Upload...');
    const nifti = path.join(files, 'DOE^JOHN.NII.GZ');
    fs.writeFileSync(nifti, crypto.randomBytes(3 * 1024 * 1024));
    await page.setInputFiles('#upload-input', nifti);
    await stateIs(page, ['opened']);
    await page.waitForFunction(() => window.vpmViewer.framesReceived > 0);
    assert.equal(await page.evaluate(() => window.vpmViewer.volume.source), 'upload:DOE^JOHN.nii.gz');
    assert.equal(await page.textContent('#message'), '', 'a volume read without notes says nothing');
    assert.equal(fake.uploads.list.at(-1).header.file_name, 'DOE^JOHN.nii.gz');

    step('a folder through Folder..., and files dropped on the page');
    const folder = path.join(files, 'SMITH^ANNA');
    fs.mkdirSync(path.join(folder, 'SE1'), { recursive: true });
    for (let i = 0; i < 4; ++i) fs.writeFileSync(path.join(folder, 'SE1', `IM${i}`), crypto.randomBytes(70000));
    fs.writeFileSync(path.join(folder, '.DS_Store'), 'junk');
    await page.setInputFiles('#upload-folder-input', folder);
    await page.waitForFunction(() => window.vpmViewer.uploads.lastVolume?.source === 'upload:SMITH^ANNA.zip',
                               null, { timeout: 20000 });
    const zip = path.join(files, 'got.zip');
    fs.writeFileSync(zip, fake.uploads.list.at(-1).bytes);
    assert.deepEqual(readZip(zip).map((m) => m.name), ['IM0', 'IM1', 'IM2', 'IM3']);
    const overlayShown = await page.evaluate(() => {
      const dt = new DataTransfer();
      for (const name of ['IM1', 'IM2']) dt.items.add(new File([new Uint8Array(70000)], name));
      document.body.dispatchEvent(new DragEvent('dragenter', { dataTransfer: dt, bubbles: true }));
      const shown = !document.getElementById('upload-drop').hidden;
      document.body.dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
      return shown && document.getElementById('upload-drop').hidden;
    });
    assert.ok(overlayShown, 'the drop overlay shows while files are dragged, and goes on the drop');
    await page.waitForFunction(() => window.vpmViewer.uploads.lastVolume?.source === 'upload:IM1.zip',
                               null, { timeout: 20000 });
    await stateIs(page, ['opened'], 60000);
    // What the reader chose from the folder is on the message line.
    await page.waitForFunction(() => document.getElementById('message').textContent ===
      'Read from upload:IM1.zip: the folder holds 2 series; read series 2 (1.2.3.4, CT ' +
      '"axial", 4 slices); ?series=N or ?series=UID picks another.', null, { timeout: 20000 });

    step('refusals: over the cap in the page, the server\'s in words');
    const sent = fake.uploads.list.length;
    const big = path.join(files, 'big.nrrd');
    fs.writeFileSync(big, Buffer.alloc(kCapBytes + 1));
    await page.setInputFiles('#upload-input', big);
    await stateIs(page, ['error']);
    assert.match(await page.evaluate(() => window.vpmViewer.uploads.lastError.message),
                 /^big\.nrrd is 4\.0 MiB; this gateway takes uploads of at most 4\.0 MiB\.$/);
    assert.equal(fake.uploads.list.length, sent);
    const bad = path.join(files, 'bad.nii');
    fs.writeFileSync(bad, Buffer.concat([Buffer.from('bad'), Buffer.alloc(1000)]));
    await page.setInputFiles('#upload-input', bad);
    await page.waitForFunction(() => /cannot read/.test(window.vpmViewer.uploads.lastError?.message));
    assert.match(await page.textContent('#message'), /^vpm-server cannot read bad\.nii as a volume: /);

    step('Cancel while the server reads');
    fake.uploads.readMs = 5000;
    await page.setInputFiles('#upload-input', nifti);
    await page.waitForFunction(
        () => document.getElementById('message').textContent.includes('reading on the ' + 'server'),
        null, { timeout: 20000 });
    const reading = await layout(page);
    assert.ok(reading.rowHeight < 40 && reading.pageWidth <= 1280, JSON.stringify(reading));
    await page.screenshot({ path: path.join(out, 'web_upload_page_reading.png') });
    await page.click('#upload-cancel');
    await stateIs(page, ['cancelled']);
    const deadline = Date.now() + 2000;
    while (!fake.uploads.list.at(-1).cancelled) {
      assert.ok(Date.now() < deadline, 'the server\'s call is cancelled');
      await new Promise((r) => setTimeout(r, 20));
    }
    // The bar and Cancel take the buttons' place: the views do not move.
    assert.equal((await layout(page)).frameTop, reading.frameTop);
  } finally {
    await browser.close();
    fake.stop();
    fs.rmSync(files, { recursive: true, force: true });
  }
}

runScenario('web_upload_page', main);

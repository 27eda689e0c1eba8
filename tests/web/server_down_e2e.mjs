// What the page says when something is missing, and that it recovers on its
// own, in headless Chromium:
//  1. the gateway points at a port where no vpm-server listens: the page
//     says the server is not reachable, and so does an Open;
//  2. vpm-server starts on that port: the page notices (gateway probes with
//     backoff), opens the volume it was asked for, and frames arrive;
//  3. a gateway whose viewer token the server does not know: the page says so;
//  4. the gateway stops: the page says so; it restarts on the same port
//     (same cookie key: the sign-in survives):
//     the page reconnects and reopens the volume;
//  5. that server keeps no cases: the Cases panel and Ctrl+Z say so; it
//     restarts with --state-dir: the page reopens the volume, now a case;
//  6. after a kept drag vpm-server is killed (SIGKILL) and restarted on the
//     same port and state dir: the page reopens the same case (OpenCase,
//     nothing clicked) with the same largest displacement (within 1e-3 mm);
//  7. the gateway restarts again: the page is back in the same case.
// Usage: node server_down_e2e.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import path from 'node:path';

import {
  canvasGrey, closedPort, freshStateDir, killChild, launchBrowser, randomToken, refreshCases,
  settled, startGateway, startServer, runScenario, stopChild, testPaths,
} from './harness.mjs';

const { build, source, out } = testPaths(process.argv);
const token = randomToken();
const step = (text) => console.log(`web_server_down: ${text}`);
const kReplayToleranceMm = 1e-3;  // a reopened case's largest displacement, mm

async function errorMessage(page, pattern, timeoutMs = 15000) {
  await page.waitForFunction(
    (source) => {
      const m = document.getElementById('message');
      return m.dataset.kind === 'error' && new RegExp(source).test(m.textContent);
    }, pattern.source, { timeout: timeoutMs, polling: 100 })
    .catch(async (e) => {
      const text = await page.textContent('#message');
      throw new Error(`no error message matching ${pattern} (shown: '${text}'): ${e.message}`);
    });
  return page.textContent('#message');
}

// 5. The server keeps no cases: the panel and Ctrl+Z say so. It restarts
// with a state dir: the page reopens the volume as a new case. Returns the
// new server.
async function startKeepingCases(page, server, port, stateDir) {
  const { kept, cases } = await refreshCases(page);
  const note = await page.textContent('#cases-note');
  step(`no --state-dir: the Cases panel says '${note}'`);
  assert.equal(kept, false);
  assert.deepEqual(cases, []);
  assert.match(note, /this server keeps no cases \(started without --state-dir\)/);
  await page.keyboard.press('Control+z');
  const text = await errorMessage(
    page, /^Undo: this server keeps no cases \(started without --state-dir\)/);
  step(`Ctrl+Z without --state-dir: ${text}`);
  await stopChild(server.child);
  await errorMessage(page, /is not reachable/);
  const keeping = await startServer({ build, out, token, port, stateDir,
                                      logName: 'server_down_cases.log' });
  await page.waitForFunction(() => /^case-/.test(window.vpmViewer.session?.case_id ?? ''), null,
                             { timeout: 60000, polling: 100 });
  await settled(page, '!h.interactive', 60000);
  const caseId = await page.evaluate(() => window.vpmViewer.caseId);
  const listed = (await refreshCases(page)).cases.map((c) => c.case_id);
  step(`restarted with --state-dir: the page reopened the volume as ${caseId}; listed: ${listed}`);
  assert.ok(listed.includes(caseId));
  return keeping;
}

// A kept drag on the 3D view; resolves with its still frame's header.
async function keptDrag(page) {
  await page.check('#keep-drag');
  await page.check('input[name="tool"][value="grab"]');
  const box = await page.locator('#frame').boundingBox();
  const c = [box.x + box.width / 2, box.y + box.height / 2];
  await page.mouse.move(c[0], c[1]);
  await page.mouse.down();
  await page.mouse.move(c[0] + 20, c[1] - 25, { steps: 10 });
  await page.mouse.up();
  return settled(page, '!h.interactive && h.max_displacement_mm > 0', 60000);
}

// Waits until the page shows case `caseId` again in a still frame with the
// largest displacement `mm`; returns the header.
async function backInCase(page, caseId, mm, framesBefore) {
  await page.waitForFunction(([id, n]) => window.vpmViewer.session?.case_id === id &&
                             window.vpmViewer.framesReceived > n, [caseId, framesBefore],
                             { timeout: 60000, polling: 100 })
    .catch(async (e) => {
      const v = await page.evaluate(() => ({ session: window.vpmViewer.session,
                                             errors: window.vpmViewer.errors }));
      throw new Error(`the page is not back in ${caseId}: ${e.message}\n${JSON.stringify(v)}`);
    });
  return settled(page, `!h.interactive && Math.abs(h.max_displacement_mm - ${mm}) < ` +
                 `${kReplayToleranceMm}`, 30000);
}

// What the page asked to open, for the log.
const asked = (opens) => JSON.stringify(opens.map((m) => [m.type, m.case_id ?? m.source]));

// The page asked for case `caseId` (open_case), and for nothing else.
function assertReopened(opens, caseId) {
  assert.ok(opens.length >= 1 && opens.every((m) => m.type === 'open_case' && m.case_id === caseId),
            `the page did not reopen the case: ${asked(opens)}`);
}

// 6. A kept drag; vpm-server (`keeping`) is killed with SIGKILL and started
// again on `port` and `stateDir`: the page opens the same case by itself,
// a new session with the same largest displacement (frame and list).
// `opens`: what the page asks to open. Returns {caseId, keptMm}.
async function killedServerReopensTheCase({ page, keeping, port, stateDir, opens }) {
  const kept = await keptDrag(page);
  const keptMm = kept.max_displacement_mm;
  const [caseId, sessionBefore, framesBefore] = await page.evaluate(() => [
    window.vpmViewer.caseId, window.vpmViewer.session.session_id, window.vpmViewer.framesReceived]);
  step(`kept drag in ${caseId}: largest displacement ${keptMm.toFixed(4)} mm`);
  opens.length = 0;
  await killChild(keeping.child);
  const text = await errorMessage(page, /is not reachable/);
  step(`vpm-server killed: ${text}`);
  const tKill = performance.now();
  await startServer({ build, out, token, port, stateDir, logName: 'server_down_killed.log' });
  const back = await backInCase(page, caseId, keptMm, framesBefore);
  step(`restarted on the same state dir: the page is back in ${caseId} after ` +
       `${Math.round(performance.now() - tKill)} ms, largest displacement ` +
       `${back.max_displacement_mm.toFixed(4)} mm (before ${keptMm.toFixed(4)}, ` +
       `|difference| ${Math.abs(back.max_displacement_mm - keptMm).toExponential(1)} mm); ` +
       `it asked for ${asked(opens)}`);
  assertReopened(opens, caseId);
  assert.notEqual(await page.evaluate(() => window.vpmViewer.session.session_id), sessionBefore,
                  'the killed server\'s session is still shown');
  const listed = (await refreshCases(page)).cases.find((c) => c.case_id === caseId);
  assert.ok(Math.abs(listed.max_displacement_mm - keptMm) < kReplayToleranceMm,
            `listed ${listed.max_displacement_mm} mm, kept ${keptMm} mm`);
  assert.match(await page.textContent('#status'), new RegExp(`case .*\\(${caseId}\\)`));
  return { caseId, keptMm };
}

async function main() {
  const port = await closedPort();
  const address = `127.0.0.1:${port}`;
  const gateway = await startGateway({ source, out, serverAddress: address, token,
                                       logName: 'gateway_down.log' });
  const browser = await launchBrowser(source);
  const page = await browser.newPage({ bypassCSP: true });  // string predicates
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
  const opens = [];  // what the page asks the gateway to open (open, open_case)
  page.on('websocket', (ws) => ws.on('framesent', ({ payload }) => {
    try {
      const m = JSON.parse(String(payload));
      if (m.type === 'open' || m.type === 'open_case') opens.push(m);
    } catch { /* not JSON */ }
  }));
  await page.goto(`${gateway.url}?token=${token}`);  // signs in, redirected to the page

  // 1. No server.
  let text = await errorMessage(page, /vpm-server at 127\.0\.0\.1:\d+ is not reachable/);
  step(`no server: ${text}`);
  assert.equal(await page.getAttribute('#server-state', 'data-state'), 'down');
  await page.selectOption('#volume', 'source:phantom:abdomen?size=128');
  await page.selectOption('#frame-size', '256');
  await page.click('#open');
  text = await errorMessage(page, /^Loading phantom:abdomen\?size=128: vpm-server at .* is not reachable/);
  step(`open without a server: ${text}`);
  assert.equal(await page.evaluate(() => window.vpmViewer.framesReceived), 0);

  // 2. The server comes up on that port: the page opens the volume by itself.
  const tUp = performance.now();
  const server = await startServer({ build, out, token, port, logName: 'server_down.log' });
  await page.waitForSelector('#server-state[data-state="up"]', { timeout: 20000 });
  await settled(page, '!h.interactive', 120000);
  const grey = await canvasGrey(page);
  step(`server up: first frame ${Math.round(performance.now() - tUp)} ms after start, ` +
       `variance ${grey.variance.toFixed(1)}`);
  assert.ok(grey.variance > 50, 'the frame after the server came up is blank');

  // 3. A gateway with the wrong token.
  const wrong = await startGateway({ source, out, serverAddress: server.address,
                                     token: 'not-the-token', logName: 'gateway_wrong_token.log' });
  const page2 = await browser.newPage({ bypassCSP: true });
  await page2.goto(`${wrong.url}?token=not-the-token`);
  text = await errorMessage(page2, /does not know the token you signed in with/);
  step(`wrong token: ${text}`);
  await page2.close();
  await stopChild(wrong.child);

  // 4. The gateway goes away and comes back on the same port.
  await stopChild(gateway.child);
  text = await errorMessage(page, /connection to the web gateway/);
  step(`gateway stopped: ${text}`);
  const before = await page.evaluate(() => window.vpmViewer.framesReceived);
  const restarted = await startGateway({ source, out, serverAddress: server.address, token,
                                        port: gateway.port, logName: 'gateway_restarted.log' });
  await page.waitForFunction((n) => window.vpmViewer.framesReceived > n, before,
                             { timeout: 60000, polling: 100 });
  await settled(page, '!h.interactive', 60000);
  step('gateway restarted: the page reconnected and frames arrive again');
  await page.screenshot({ path: path.join(out, 'web_reconnected.png') });

  // 5. Cases: none kept, then a server with a state dir.
  const stateDir = freshStateDir(out, 'server-down-state');
  const keeping = await startKeepingCases(page, server, port, stateDir);

  // 6. A kept drag; the server is killed and restarted on the same state dir.
  const { caseId, keptMm } = await killedServerReopensTheCase({ page, keeping, port, stateDir, opens });

  // 7. The gateway restarts: the page is back in the same case.
  const framesBefore = await page.evaluate(() => window.vpmViewer.framesReceived);
  opens.length = 0;
  await stopChild(restarted.child);
  await errorMessage(page, /connection to the web gateway/);
  await startGateway({ source, out, serverAddress: server.address, token, port: gateway.port,
                       logName: 'gateway_restarted_again.log' });
  const again = await backInCase(page, caseId, keptMm, framesBefore);
  step(`gateway restarted: the page is back in ${caseId}, largest displacement ` +
       `${again.max_displacement_mm.toFixed(4)} mm (|difference| ` +
       `${Math.abs(again.max_displacement_mm - keptMm).toExponential(1)} mm); it asked for ${asked(opens)}`);
  assertReopened(opens, caseId);
  await page.screenshot({ path: path.join(out, 'web_reconnected_case.png') });
  assert.deepEqual(pageErrors, [], 'the page threw');
  await browser.close();
}

runScenario('web_server_down', main);

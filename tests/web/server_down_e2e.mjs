// What the page says when something is missing, and that it recovers on its
// own, in headless Chromium:
//  1. the gateway points at a port where no vpm-server listens: the page
//     says the server is not reachable, and so does an Open;
//  2. vpm-server starts on that port: the page notices (gateway probes with
//     backoff), opens the volume it was asked for, and frames arrive;
//  3. a gateway whose viewer token the server does not know: the page says so;
//  4. the gateway stops: the page says so; it restarts on the same port
//     (same cookie key: the sign-in survives):
//     the page reconnects and reopens the volume.
// Usage: node server_down_e2e.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import path from 'node:path';

import {
  canvasGrey, closedPort, launchBrowser, randomToken, settled, startGateway, startServer,
  runScenario, stopChild, testPaths,
} from './harness.mjs';

const { build, source, out } = testPaths(process.argv);
const token = randomToken();
const step = (text) => console.log(`web_server_down: ${text}`);

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

async function main() {
  const port = await closedPort();
  const address = `127.0.0.1:${port}`;
  const gateway = await startGateway({ source, out, serverAddress: address, token,
                                       logName: 'gateway_down.log' });
  const browser = await launchBrowser(source);
  const page = await browser.newPage({ bypassCSP: true });  // string predicates
  const pageErrors = [];
  page.on('pageerror', (e) => pageErrors.push(e.message));
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
  await startGateway({ source, out, serverAddress: server.address, token, port: gateway.port,
                       logName: 'gateway_restarted.log' });
  await page.waitForFunction((n) => window.vpmViewer.framesReceived > n, before,
                             { timeout: 60000, polling: 100 });
  await settled(page, '!h.interactive', 60000);
  step('gateway restarted: the page reconnected and frames arrive again');
  await page.screenshot({ path: path.join(out, 'web_reconnected.png') });
  assert.deepEqual(pageErrors, [], 'the page threw');
  await browser.close();
}

runScenario('web_server_down', main);

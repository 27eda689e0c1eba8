// What the web viewer's end-to-end tests share: starting vpm-server and the
// gateway on ephemeral ports, driving Debian's Chromium through
// playwright-core (executablePath: no browser is downloaded), and reading
// the frame canvas back.
import { spawn } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import { createRequire } from 'node:module';
import net from 'node:net';
import path from 'node:path';

export const kChromium = process.env.VPM_CHROMIUM ?? '/usr/bin/chromium';

// argv: --build DIR --source DIR; returns absolute paths and the output
// folder (BUILD/tests/web), created.
export function testPaths(argv) {
  const arg = (name) => {
    const i = argv.indexOf(name);
    if (i < 0 || !argv[i + 1]) throw new Error(`missing ${name} DIR`);
    return path.resolve(argv[i + 1]);
  };
  const build = arg('--build');
  const source = arg('--source');
  const out = path.join(build, 'tests', 'web');
  fs.mkdirSync(out, { recursive: true });
  return { build, source, out };
}

// Resolves once a line of the child's stdout or stderr matches `pattern`
// (with the match); rejects when the child exits first or after timeoutMs.
export function waitForLine(child, pattern, what, timeoutMs, logFile) {
  const log = fs.createWriteStream(logFile);
  return new Promise((resolve, reject) => {
    let seen = '';
    const timer = setTimeout(
      () => reject(new Error(`${what} did not start in ${timeoutMs} ms; its output:\n${seen}`)),
      timeoutMs);
    const onData = (chunk) => {
      log.write(chunk);
      seen += chunk.toString();
      const m = pattern.exec(seen);
      if (m) {
        clearTimeout(timer);
        resolve(m);
      }
    };
    child.stdout.on('data', onData);
    child.stderr.on('data', onData);
    child.on('exit', (code, signal) => {
      clearTimeout(timer);
      reject(new Error(`${what} exited (${code ?? signal}) before it was ready:\n${seen}`));
    });
  });
}

const children = new Set();

export function track(child) {
  children.add(child);
  child.on('exit', () => children.delete(child));
  return child;
}

// Stops every child this process started (SIGTERM, then SIGKILL after 3 s).
export async function stopAll() {
  await Promise.all([...children].map((c) => stopChild(c)));
}

export function stopChild(child) {
  if (child.exitCode !== null || child.signalCode !== null) return Promise.resolve();
  return new Promise((resolve) => {
    const kill = setTimeout(() => child.kill('SIGKILL'), 3000);
    child.on('exit', () => {
      clearTimeout(kill);
      resolve();
    });
    child.kill('SIGTERM');
  });
}

// A fresh, empty folder under `out` for a server's --state-dir.
export function freshStateDir(out, name) {
  const dir = path.join(out, name);
  fs.rmSync(dir, { recursive: true, force: true });
  fs.mkdirSync(dir, { recursive: true });
  return dir;
}

// Kills `child` with SIGKILL (no shutdown of its own) and waits for it.
export function killChild(child) {
  if (child.exitCode !== null || child.signalCode !== null) return Promise.resolve();
  return new Promise((resolve) => {
    child.on('exit', () => resolve());
    child.kill('SIGKILL');
  });
}

export const randomToken = () => crypto.randomBytes(16).toString('hex');

// A users file (vpm-server's --users format) for {name: token}; returns its path.
export function writeUsersFile(file, users) {
  const sha256 = (t) => crypto.createHash('sha256').update(t).digest('hex');
  fs.writeFileSync(file, Object.entries(users).map(([n, t]) => `${n} ${sha256(t)}\n`).join(''));
  return file;
}

// vpm-server on 127.0.0.1:port (0: ephemeral) with `token` (its user
// `default`) and any further `args`; with `stateDir` it keeps cases there
// (--state-dir, docs/CASES.md). Resolves with {child, port, address,
// metricsPort} (metricsPort with `--metrics-listen` among the args).
export async function startServer({ build, out, token, port = 0, logName = 'server.log',
                                    stateDir = null, args = [] }) {
  const binary = path.join(build, 'server', 'service', 'vpm-server');
  if (!fs.existsSync(binary)) throw new Error(`${binary} is missing: build the vpm-server target`);
  const cases = stateDir ? ['--state-dir', stateDir] : [];
  const child = track(spawn(binary, ['--listen', `127.0.0.1:${port}`, ...cases, ...args], {
    env: { ...process.env, VPM_TOKEN: token }, stdio: ['ignore', 'pipe', 'pipe'] }));
  const m = await waitForLine(child, /vpm-server listening on port (\d+)( metrics on port (\d+))?/,
                              'vpm-server', 30000, path.join(out, logName));
  return { child, port: Number(m[1]), address: `127.0.0.1:${m[1]}`,
           metricsPort: m[3] ? Number(m[3]) : null };
}

// The gateway on 127.0.0.1:port (0: ephemeral), talking to `serverAddress`;
// `token` is its viewer token (VPM_TOKEN: a browser signs in with it and the
// gateway forwards it to the server); `args`: more flags. Sign-ins are sealed
// with a key kept in `out`, so they survive a restart of the gateway.
// Resolves with {child, url, port}.
export async function startGateway({ source, out, serverAddress, token, port = 0,
                                     logName = 'gateway.log', args = [] }) {
  const keyFile = path.join(out, 'gateway-cookie.key');
  if (!fs.existsSync(keyFile)) fs.writeFileSync(keyFile, crypto.randomBytes(32), { mode: 0o600 });
  const child = track(spawn(process.execPath, [
    path.join(source, 'client', 'web', 'gateway.js'),
    '--listen', `127.0.0.1:${port}`, '--server', serverAddress, '--cookie-key-file', keyFile,
    ...args], {
    env: { ...process.env, VPM_TOKEN: token }, stdio: ['ignore', 'pipe', 'pipe'] }));
  const m = await waitForLine(child, /vpm-web listening on (http:\/\/\S+:(\d+)\/)/, 'the gateway',
                              15000, path.join(out, logName));
  return { child, url: m[1], port: Number(m[2]) };
}

// Signs `page` in at the gateway `url` through the sign-in form (where the
// gateway sends a browser without a cookie) and waits for the viewer.
export async function signInWithForm(page, url, token) {
  await page.goto(url);
  await page.waitForSelector('#login', { timeout: 10000 });
  await page.fill('#token', token);
  await Promise.all([page.waitForURL((u) => !u.pathname.startsWith('/login'), { timeout: 10000 }),
                     page.click('#sign-in')]);
  await page.waitForSelector('#frame', { timeout: 10000 });
}

// A port nothing listens on (bound, then released).
export function closedPort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.on('error', reject);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => resolve(port));
    });
  });
}

// Headless Chromium through playwright-core from client/web/node_modules.
export async function launchBrowser(source) {
  const require = createRequire(path.join(source, 'client', 'web', 'package.json'));
  const { chromium } = require('playwright-core');
  if (!fs.existsSync(kChromium)) throw new Error(`${kChromium} is missing: install chromium`);
  return chromium.launch({ executablePath: kChromium, headless: true });
}

// A canvas as grey levels (0..255, one per pixel, rows of `width`) with its
// size, mean and variance.
export async function canvasGrey(page, id = 'frame') {
  return page.evaluate((canvasId) => {
    const c = document.getElementById(canvasId);
    const rgba = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const grey = new Array(rgba.length / 4);
    let sum = 0, sum2 = 0;
    for (let i = 0; i < grey.length; ++i) {
      const g = 0.299 * rgba[4 * i] + 0.587 * rgba[4 * i + 1] + 0.114 * rgba[4 * i + 2];
      grey[i] = g;
      sum += g;
      sum2 += g * g;
    }
    const mean = sum / grey.length;
    return { grey, width: c.width, height: c.height, mean,
             variance: sum2 / grey.length - mean * mean };
  }, id);
}

// Mean absolute grey difference between two canvasGrey results.
export function meanAbsDiff(a, b) {
  if (a.grey.length !== b.grey.length) return Infinity;
  let sum = 0;
  for (let i = 0; i < a.grey.length; ++i) sum += Math.abs(a.grey[i] - b.grey[i]);
  return sum / a.grey.length;
}

// Waits until every event sent so far is reflected in a drawn frame that
// matches `extra` (a function body over v = window.vpmViewer and h = its
// last frame header); returns the header.
export async function settled(page, extra = 'true', timeoutMs = 20000) {
  const expression = `(() => { const v = window.vpmViewer; const h = v.lastHeader;
    return !!h && h.last_sequence >= v.sequence &&
      v.framesDrawn + v.framesSuperseded >= v.framesReceived &&
      (${extra}); })()`;
  await page.waitForFunction(expression, null, { timeout: timeoutMs, polling: 50 }).catch(async (e) => {
    const v = await page.evaluate(() => ({
      sequence: window.vpmViewer.sequence, header: window.vpmViewer.lastHeader,
      errors: window.vpmViewer.errors, message: document.getElementById('message').textContent }));
    throw new Error(`frame never settled (${extra}): ${e.message}\n${JSON.stringify(v)}`);
  });
  return page.evaluate(() => window.vpmViewer.lastHeader);
}

// Asks the page's Cases panel for the list again; resolves with {kept,
// cases} (window.vpmViewer) once the gateway has answered. The button is
// clicked from the page, so that the page does not scroll (the tests' mouse
// positions on the canvases stay right).
export async function refreshCases(page) {
  const n = await page.evaluate(() => window.vpmViewer.casesListed);
  await page.evaluate(() => document.getElementById('cases-refresh').click());
  await page.waitForFunction((k) => window.vpmViewer.casesListed > k, n,
                             { timeout: 15000, polling: 50 });
  return page.evaluate(() => ({ kept: window.vpmViewer.casesKept,
                                cases: window.vpmViewer.casesPanel.cases }));
}

// Presses `keys` (e.g. 'Control+z') on the page; resolves with the
// gateway's answer to the undo or redo (an 'undone' message), or rejects
// with the error the page got instead.
export async function pressUndoKeys(page, keys) {
  const [answers, errors] = await page.evaluate(() => [window.vpmViewer.undoAnswers,
                                                       window.vpmViewer.errors.length]);
  await page.keyboard.press(keys);
  await page.waitForFunction(([a, e]) => window.vpmViewer.undoAnswers > a ||
                             window.vpmViewer.errors.length > e, [answers, errors],
                             { timeout: 20000, polling: 50 });
  const v = await page.evaluate((e) => ({ answer: window.vpmViewer.lastUndo,
                                          error: window.vpmViewer.errors[e] ?? null }), errors);
  if (v.error) throw new Error(`${keys}: the page got an error: ${JSON.stringify(v.error)}`);
  return v.answer;
}

// Runs a scenario's main(): prints "NAME: PASS", or the failure and exits 1;
// either way stops every child started.
export function runScenario(name, main) {
  main()
    .then(() => stopAll())
    .then(() => console.log(`${name}: PASS`))
    .catch(async (e) => {
      console.error(`${name}: FAIL: ${e.stack ?? e}`);
      await stopAll();
      process.exit(1);
    });
}

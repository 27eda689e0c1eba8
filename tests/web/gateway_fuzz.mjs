// The gateway survives hostile input: at least 5,000 malformed HTTP requests
// (random bytes, broken request lines and paths, bad UTF-8 and percent
// escapes, huge and duplicated headers, forged and oversized cookies, bad
// Host and Origin, broken bodies and chunking, bad WebSocket upgrades) and at
// least 5,000 WebSocket frames on signed-in connections (random bytes,
// unmasked, reserved opcodes and bits, bad UTF-8, lengths up to 2^63,
// fragmented control frames, bad JSON, wrong types, messages out of order,
// the case messages against a server that keeps cases, the Studies panel's
// and Export's messages against a server with a PACS endpoint).
// Then the gateway must still run, answer /healthz and serve a real client
// (sign in, open a volume, frames, an event). The gateway runs against the
// stand-in server (fake_vpm_server.mjs); every input comes from a seeded
// generator (VPM_FUZZ_SEED, printed), so a failure can be replayed.
// Usage: node gateway_fuzz.mjs [--http N] [--ws N]
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import net from 'node:net';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';

import { startFakeServer } from './fake_vpm_server.mjs';
import { connect, request, signIn, startGatewayProcess } from './gateway_client.mjs';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const { values: args } = parseArgs({ options: {
  http: { type: 'string', default: '5000' }, ws: { type: 'string', default: '5500' } } });
const kHttpCount = Number(args.http);
const kWsFrames = Number(args.ws);
const seed = Number(process.env.VPM_FUZZ_SEED ?? (Date.now() % 2 ** 31));

// mulberry32: a small seeded generator, so a failing run can be replayed.
let state = seed >>> 0;
function rand() {
  state = (state + 0x6d2b79f5) >>> 0;
  let t = state;
  t = Math.imul(t ^ (t >>> 15), t | 1);
  t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
}
const int = (n) => Math.floor(rand() * n);
const pick = (list) => list[int(list.length)];
const bytes = (n) => Buffer.from(Array.from({ length: n }, () => int(256)));
const chars = (n, alphabet) => Array.from({ length: n }, () => pick(alphabet)).join('');
const kAscii = [...'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789/.%?&=#-_~:@!$\'()*+,;[] '];

// ---------------------------------------------------------------- HTTP

function randomPath() {
  return pick([
    () => `/${chars(int(40), kAscii)}`,
    () => `/${pick(['%', '%z', '%zz', '%c0%af', '%ff%fe', '%00', '%e2%82', '..%2f..%2f'])}${chars(int(8), kAscii)}`,
    () => `/${'a'.repeat(1000 + int(100000))}`,
    () => pick(['/', '/login', '/logout', '/whoami', '/ws', '/healthz', '/app.js', '/style.css']) +
          pick(['', '?token=', `?token=${chars(int(64), kAscii)}`, `?token=${'x'.repeat(5000)}`, '?%', '#x']),
    () => pick(['*', 'http://evil.example/', '//double', '/../../etc/passwd', '/.git/config',
                '\\windows', '/\u00e9\u4e2d', '/%2e%2e/%2e%2e/gateway.js']),
    () => bytes(int(30)).toString('latin1'),
  ])();
}

// Header lines; with `wellFormed`, only lines the HTTP parser accepts (the
// values still hostile), so the request reaches the gateway's own code.
function randomHeaders(port, wellFormed = false) {
  const headers = [];
  const n = int(8);
  for (let i = 0; i < n; ++i) {
    headers.push(pick((wellFormed ? (l) => l.slice(0, 13) : (l) => l)([
      () => `Host: ${pick(['127.0.0.1', 'localhost', 'evil.example', '', '[::1]', '[zz', 'a'.repeat(300)])}:${pick([port, 0, 99999, 'x'])}`,
      () => `Cookie: vpm_session=${pick([chars(int(200), kAscii), crypto.randomBytes(int(200)).toString('base64url'), 'x'.repeat(9000), ''])}`,
      () => `Cookie: ${chars(int(100), kAscii)}`,
      () => `Origin: ${pick(['null', 'http://evil.example', `http://127.0.0.1:${port}`, chars(int(50), kAscii), 'x'.repeat(400)])}`,
      () => `Content-Length: ${pick([0, 5, -1, 'abc', 99999999999, 1e30])}`,
      () => `Transfer-Encoding: ${pick(['chunked', 'gzip, chunked', 'bogus'])}`,
      () => `Content-Type: ${pick(['application/x-www-form-urlencoded', 'text/plain', '', 'multipart/form-data; boundary=x'])}`,
      () => `Upgrade: ${pick(['websocket', 'WebSocket', 'h2c', ''])}`,
      () => `Connection: ${pick(['Upgrade', 'keep-alive', 'close', 'upgrade, keep-alive'])}`,
      () => `Sec-WebSocket-Key: ${pick(['dGhlIHNhbXBsZSBub25jZQ==', 'short', '', crypto.randomBytes(16).toString('base64')])}`,
      () => `Sec-WebSocket-Version: ${pick([13, 8, 99, 'x'])}`,
      () => `Accept: ${chars(int(30), kAscii)}`,
      () => `X-${chars(1 + int(20), kAscii.filter((c) => /[A-Za-z0-9-]/.test(c)))}: ${chars(int(100), kAscii)}`,
      () => `Big: ${'b'.repeat(int(40000))}`,
      () => `${chars(int(20), kAscii)}`,  // not a header line
      () => `Bad\u0000Header: ${bytes(10).toString('latin1')}`,
    ]))());
  }
  return headers;
}

const kPathChars = kAscii.filter((c) => c !== ' ' && c !== '#');

function randomHttpRequest(port) {
  const kind = int(10);
  if (kind === 0) return bytes(int(3000));
  if (kind === 1) return Buffer.from(`${chars(int(30), kAscii)}\r\n\r\n`);
  if (kind < 7) {
    // Parses as HTTP: hostile values where the gateway's code reads them.
    const target = pick([
      () => `/${chars(int(40), kPathChars)}`,
      () => pick(['/', '/login', '/logout', '/whoami', '/ws', '/app.js', '/%', '/%zz', '/%c0%af',
                  '/%2e%2e/gateway.js', '/.git/config']) +
            pick(['', '?token=', `?token=${chars(int(64), kPathChars)}`, '?%', '?token=%ff%fe']),
    ])();
    const method = pick(['GET', 'POST', 'HEAD', 'PUT', 'DELETE', 'OPTIONS']);
    const headers = [`Host: ${pick(['127.0.0.1', 'localhost', 'evil.example'])}:${port}`,
                     ...randomHeaders(port, true)]
      .filter((h) => !/^(Host|Content-Length|Transfer-Encoding|Upgrade|Connection)/.test(h) || h.startsWith(`Host: `) && h.endsWith(`:${port}`));
    const body = method === 'POST' ? pick(['', `token=${chars(int(50), kPathChars)}`, 'token=%ff',
                                           bytes(int(300)).toString('latin1')]) : '';
    return Buffer.from(`${method} ${target} HTTP/1.1\r\n${headers.join('\r\n')}\r\n` +
                       `Content-Length: ${Buffer.byteLength(body, 'latin1')}\r\n\r\n${body}`, 'latin1');
  }
  const method = pick(['GET', 'POST', 'HEAD', 'PUT', 'DELETE', 'OPTIONS', 'TRACE', 'CONNECT', 'PATCH',
                       'get', 'FOO', '', 'G\u00c9T']);
  const version = pick(['HTTP/1.1', 'HTTP/1.0', 'HTTP/2.0', 'HTTP/9', '']);
  const body = pick(['', `token=${chars(int(50), kAscii)}`, bytes(int(500)).toString('latin1'),
                     '5\r\nhello\r\n0\r\n\r\n', 'zz\r\nbad chunk\r\n', 'a'.repeat(20000)]);
  const head = [`${method} ${randomPath()} ${version}`, ...randomHeaders(port)].join('\r\n');
  return Buffer.from(`${head}\r\n\r\n${body}`, 'latin1');
}

// Sends one raw request on its own connection; resolves when the gateway
// closes it or after a short wait.
function rawRequest(port, payload) {
  return new Promise((resolve) => {
    const socket = net.connect(port, '127.0.0.1');
    let status = null;
    const done = () => {
      socket.destroy();
      resolve(status);
    };
    socket.setTimeout(1500, done);
    socket.on('data', (d) => {
      if (status !== null) return;
      status = /^HTTP\/1\.[01] (\d{3})/.exec(d.toString('latin1'))?.[1] ?? 'other';
      setTimeout(done, 20);  // the answer came (a kept-alive connection stays open)
    });
    socket.on('error', done);
    socket.on('close', done);
    socket.write(payload, () => {
      if (rand() < 0.5) socket.end();
    });
  });
}

// ---------------------------------------------------------------- WebSocket

// A client frame: FIN/RSV/opcode byte, masked payload (or not), any length
// field (the declared length may lie).
function frame({ fin = true, rsv = 0, opcode = 1, payload = Buffer.alloc(0), mask = true,
                 declared = null }) {
  const length = declared ?? payload.length;
  let header;
  if (length < 126) {
    header = Buffer.from([(fin ? 0x80 : 0) | (rsv << 4) | opcode, (mask ? 0x80 : 0) | length]);
  } else if (length < 65536) {
    header = Buffer.alloc(4);
    header[0] = (fin ? 0x80 : 0) | (rsv << 4) | opcode;
    header[1] = (mask ? 0x80 : 0) | 126;
    header.writeUInt16BE(length, 2);
  } else {
    header = Buffer.alloc(10);
    header[0] = (fin ? 0x80 : 0) | (rsv << 4) | opcode;
    header[1] = (mask ? 0x80 : 0) | 127;
    header.writeBigUInt64BE(BigInt(length), 2);
  }
  if (!mask) return Buffer.concat([header, payload]);
  const key = crypto.randomBytes(4);
  const masked = Buffer.from(payload);
  for (let i = 0; i < masked.length; ++i) masked[i] ^= key[i % 4];
  return Buffer.concat([header, key, masked]);
}

const kJunkValues = [null, true, false, 0, -1, 1e308, -1e308, 2 ** 64, 1.5, '', 'x', 'x'.repeat(5000),
                     [], [1, 2], {}, { x: 1 }, { x: 'a', y: null, z: [] }, '\u0000', '\ud800'];
function junk(depth = 0) {
  if (depth > 3 || rand() < 0.5) return pick(kJunkValues);
  if (rand() < 0.5) return Array.from({ length: int(4) }, () => junk(depth + 1));
  const o = {};
  for (let i = int(5); i > 0; --i) {
    o[pick(['type', 'event', 'source', 'volume_id', 'session_id', 'settings', 'camera', 'point_mm',
            'sequence', 'grab', 'drag', 'pull', 'release', 'x', 'y', 'z', 'mode', 'width',
            '__proto__', 'constructor', chars(5, kAscii)])] = junk(depth + 1);
  }
  return o;
}

function randomMessage() {
  const vec = () => ({ x: pick([0, 1, -5, 1e9, 'a', null]), y: rand() * 100, z: pick([0, NaN, 3]) });
  return pick([
    () => junk(),
    () => ({ type: pick(['list', 'open', 'event', 'refine', 'watch', 'close', '', null, 7, 'cases',
                         'open_case', 'rename_case', 'delete_case', 'undo']), ...junk() }),
    () => ({ type: pick(['cases', 'open_case', 'rename_case', 'delete_case', 'undo']),
             case_id: pick(['case-00000001', 'case-999', '', '../x', 'x'.repeat(200), 7, null, undefined]),
             title: pick([undefined, 'T', '', 'x'.repeat(300), 'a\nb', 7]),
             redo: pick([undefined, true, 'yes', 1]), sequence: pick([undefined, 3, -1, 'a']),
             camera: pick([undefined, null, junk()]) }),
    () => ({ type: 'open', source: pick(['phantom:loaded', 'phantom:other', '../../etc/passwd', 'x'.repeat(3000), 5]),
             settings: pick([undefined, junk(), { mode: pick(['dvr', 'mip', 'x']), width: pick([4, -1, 1e9, 'a']) }]),
             camera: pick([undefined, junk(), { azimuth_deg: 30 }]) }),
    () => ({ type: 'open', volume_id: pick(['vol-1', 'vol-999', '', 'x'.repeat(200)]) }),
    () => ({ type: 'event', event: { sequence: pick([1, -1, 2 ** 60, 'a']),
                                     [pick(['camera', 'grab', 'drag', 'pull', 'release', 'settings', 'bogus'])]: junk() } }),
    () => ({ type: 'event', event: { sequence: int(100), drag: { offset_mm: vec() } } }),
    () => ({ type: 'event', event: { sequence: int(100), grab: { pick: true, pixel_x: int(10) - 2, pixel_y: 1 } } }),
    () => ({ type: 'refine', point_mm: pick([vec(), junk()]) }),
    () => ({ type: 'watch', session_id: pick(['ses-1', 'ses-999', '', 7]), settings: junk() }),
    () => ({ type: 'event', event: { sequence: int(100), settings: {
      slices: pick([junk(), Array.from({ length: int(6) }, () => ({
        view: pick(['axial', '', 'x'.repeat(50), 7]),
        orientation: pick(['SLICE_ORIENTATION_AXIAL', 'SLICE_ORIENTATION_OBLIQUE', 'AXIAL', 3, null]),
        at_mm: pick([undefined, 1, -1e308, 'a', null]), normal: pick([undefined, vec(), junk()]),
        window: pick([undefined, { width: pick([0, -1, 400, 'a']), level: 40 }, junk()]),
        pixel_mm: pick([undefined, 0, -1, 1e-9, 1e308]), [pick(['bogus', 'overlay'])]: junk() }))]),
      uploaded_tf: pick([undefined, true, false, 'yes', junk()]),
      crop: pick([undefined, junk(), { lo_mm: vec(), hi_mm: vec() }]),
      clip: pick([undefined, junk(), [{ normal: vec(), offset_mm: pick([1, 'a']) }]]) } } }),
    () => ({ type: pick(['pacs_endpoints', 'pacs_search', 'pacs_series', 'pacs_open', 'pacs_cancel',
                         'export_dicom']),
             endpoint: pick([undefined, 'orthanc', 'nope', '', '.x', 'x'.repeat(100), 7, null]),
             patient_name: pick([undefined, 'DOE^J*', '', '*', 'é'.repeat(40), 'a\u0000b', 7]),
             study_date: pick([undefined, '20240101-', '2024', '-', junk()]),
             modality: pick([undefined, 'CT', 'C T', 'x'.repeat(20)]),
             limit: pick([undefined, 1, 0, 1001, 'a', 2 ** 60]),
             study_uid: pick([undefined, '1.2.826.0.1.3680043.8.498.1', '1..2', 'x'.repeat(100), 7]),
             source: pick([undefined, 'pacs:orthanc/1.2.826.0.1.3680043.8.498.1/1.2.826.0.1.3680043.8.498.1.1',
                           'pacs:orthanc/1.2/1.2.9', 'pacs:x', `pacs:${'x'.repeat(400)}`, 5]),
             series_description: pick([undefined, 'with files', 'x'.repeat(65), '', 7]) }),
    () => ({ type: 'tf', file_name: pick(['a.vp', 'a.json', 'a.png', '', 'x'.repeat(300), 7, null]),
             text: pick(['1\n1\n', 'bad', '', 'x'.repeat(60001), 5, null, junk()]),
             preset: pick([undefined, 'Bones', '', 7, 'x'.repeat(300)]) }),
  ])();
}

function randomWsFrame() {
  const kind = int(30);  // 0-8 end the connection; most are messages
  const text = (s) => Buffer.from(typeof s === 'string' ? s : JSON.stringify(s) ?? 'undefined', 'utf8');
  switch (kind) {
    case 0: return { data: bytes(int(200)), closes: true };
    case 1: return { data: frame({ payload: Buffer.from([0xc3, 0x28, 0xff, 0xfe, 0xed, 0xa0, 0x80]) }), closes: true };
    case 2: return { data: frame({ payload: text('{"type":"list"}'), mask: false }), closes: true };
    case 3: return { data: frame({ opcode: pick([3, 4, 5, 6, 7, 11, 12, 13, 14, 15]), payload: bytes(5) }), closes: true };
    case 4: return { data: frame({ rsv: 1 + int(7), payload: text('{}') }), closes: true };
    case 5: return { data: frame({ payload: Buffer.alloc(0), declared: pick([2 ** 40, 2 ** 53, 65 * 1024, 200000]) }), closes: true };
    case 6: return { data: frame({ opcode: pick([8, 9, 10]), fin: false, payload: bytes(3) }), closes: true };
    case 7: return { data: frame({ opcode: 0, payload: text('orphan continuation') }), closes: true };
    case 8: return { data: frame({ opcode: 9, payload: bytes(200) }), closes: true };  // control frame > 125
    case 9: return { data: frame({ opcode: 2, payload: bytes(int(1000)) }), closes: false };  // binary: refused politely
    case 10: return { data: frame({ payload: text(chars(int(100), kAscii)) }), closes: false };  // not JSON
    case 11: return { data: Buffer.concat([frame({ fin: false, payload: text('{"type":') }),
                                           frame({ opcode: 0, payload: text('"list"}') })]), closes: false };
    default: return { data: frame({ payload: text(randomMessage()) }), closes: false };
  }
}

// A signed-in WebSocket on a raw socket (frames written by hand).
function rawWebSocket(port, cookie) {
  return new Promise((resolve, reject) => {
    const socket = net.connect(port, '127.0.0.1');
    const key = crypto.randomBytes(16).toString('base64');
    socket.on('error', (e) => reject(new Error(`the gateway is gone: ${e.message}`)));
    socket.on('close', () => reject(new Error('the gateway closed the upgrade')));
    socket.setTimeout(5000, () => reject(new Error('no answer to the upgrade in 5 s')));
    socket.once('data', (d) => {
      if (/^HTTP\/1\.1 101/.test(d.toString('latin1'))) resolve(socket);
      else reject(new Error(`upgrade refused: ${d.toString('latin1').split('\r\n')[0]}`));
    });
    socket.write(`GET /ws HTTP/1.1\r\nHost: 127.0.0.1:${port}\r\nUpgrade: websocket\r\n` +
                 `Connection: Upgrade\r\nSec-WebSocket-Key: ${key}\r\nSec-WebSocket-Version: 13\r\n` +
                 `Origin: http://127.0.0.1:${port}\r\nCookie: ${cookie}\r\n\r\n`);
  });
}

async function fuzzWebSocket(port, cookie, frames, lane) {
  let sent = 0;
  let connections = 0;
  while (sent < frames) {
    const socket = await rawWebSocket(port, cookie);
    socket.setTimeout(0);
    connections += 1;
    let closed = false;
    socket.on('close', () => { closed = true; });
    socket.on('data', () => {});
    for (let i = 0; i < 50 && sent < frames && !closed; ++i) {
      const f = randomWsFrame();
      socket.write(f.data);
      sent += 1;
      if (f.closes) break;
      if (i % 10 === 0) await new Promise((r) => setTimeout(r, 1));
    }
    await new Promise((r) => setTimeout(r, closed ? 0 : 5));
    socket.destroy();
  }
  return { lane, sent, connections };
}

// ---------------------------------------------------------------- main

async function main() {
  console.log(`gateway_fuzz: seed ${seed} (VPM_FUZZ_SEED=${seed} replays it)`);
  const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-gateway-fuzz-'));
  const token = crypto.randomBytes(16).toString('hex');
  fs.writeFileSync(path.join(tmp, 'users.txt'),
                   `alice ${crypto.createHash('sha256').update(token).digest('hex')}\n`);
  const fake = await startFakeServer(source);
  fake.keepCases(true);  // the case messages reach a server that keeps cases
  fake.setPacs([{ name: 'orthanc', users: ['*'] }]);  // and the PACS messages one with a PACS
  const log = fs.openSync(path.join(tmp, 'gateway.log'), 'w');
  const { child, base } = await startGatewayProcess({
    source, args: ['--server', fake.address, '--users', path.join(tmp, 'users.txt')],
    stderr: log });
  const port = Number(new URL(base).port);
  let exited = null;
  child.on('exit', (code, signal) => { exited = code ?? signal; });
  try {
    // Signed in before the HTTP fuzz throttles this address's sign-ins.
    const cookie = await signIn(base, token);
    const t0 = performance.now();

    const statuses = new Map();
    let next = 0;
    await Promise.all(Array.from({ length: 32 }, async () => {
      while (next < kHttpCount && exited === null) {
        next += 1;
        const s = await rawRequest(port, randomHttpRequest(port));
        statuses.set(s, (statuses.get(s) ?? 0) + 1);
      }
    }));
    const tHttp = performance.now();
    assert.equal(exited, null, `the gateway exited (${exited}) during the HTTP fuzz`);
    console.log(`gateway_fuzz: ${kHttpCount} malformed HTTP requests in ${((tHttp - t0) / 1000).toFixed(1)} s; ` +
                `answers: ${JSON.stringify(Object.fromEntries(statuses))}`);

    const lanes = await Promise.all([0, 1, 2, 3].map((lane) =>
      fuzzWebSocket(port, cookie, Math.ceil(kWsFrames / 4), lane)));
    const frames = lanes.reduce((n, l) => n + l.sent, 0);
    const connections = lanes.reduce((n, l) => n + l.connections, 0);
    assert.equal(exited, null, `the gateway exited (${exited}) during the WebSocket fuzz`);
    console.log(`gateway_fuzz: ${frames} WebSocket frames on ${connections} signed-in connections ` +
                `in ${((performance.now() - tHttp) / 1000).toFixed(1)} s`);
    assert.ok(kHttpCount + frames >= 10000, 'fewer than 10,000 inputs');

    // Still alive, and a real client is served.
    await new Promise((r) => setTimeout(r, 500));
    assert.equal(exited, null, `the gateway exited (${exited})`);
    assert.equal((await request(base, '/healthz')).status, 200);
    const page = await request(base, '/', { headers: { Cookie: cookie } });
    assert.equal(page.status, 200);
    const tab = await connect(source, base, { cookie });
    tab.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4 } });
    await tab.next((m) => m.type === 'opened');
    await tab.next((m) => m.type === 'frame');
    tab.send({ type: 'event', event: { sequence: 5, drag: { offset_mm: { x: 1, y: 0, z: 0 } } } });
    await tab.next((m) => m.type === 'error' || (m.type === 'frame' && m.header.last_sequence === 5));
    tab.ws.close();
    const text = fs.readFileSync(path.join(tmp, 'gateway.log'), 'utf8');
    const unexpected = text.split('\n').filter((l) => /unexpected error|failed: /.test(l));
    console.log(`gateway_fuzz: after the fuzz a real client signed in, opened, got frames; ` +
                `${unexpected.length} connections closed on an unexpected error`);
    assert.deepEqual(unexpected.slice(0, 5), [], 'errors the gateway did not expect');
    console.log('gateway_fuzz: PASS');
  } finally {
    child.kill('SIGTERM');
    fake.stop();
    fs.rmSync(tmp, { recursive: true, force: true });
  }
}

main().catch((e) => {
  console.error(`gateway_fuzz: FAIL (seed ${seed}): ${e.stack ?? e}`);
  process.exit(1);
});

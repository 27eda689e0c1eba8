// The gateway (client/web/gateway.js) against a stand-in server
// (fake_vpm_server.mjs), through a WebSocket as the page uses it: the token
// and a per-tab affinity key on every call, reuse of a loaded volume,
// frames in the binary format, an event error reopening the stream with the
// camera and settings replayed, the session closed with the tab, and what
// the HTTP side refuses.
// Usage: node --test gateway.test.mjs (SOURCE is found from this file).
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import http from 'node:http';
import { createRequire } from 'node:module';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { startFakeServer } from './fake_vpm_server.mjs';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const WebSocket = createRequire(path.join(source, 'client', 'web', 'package.json'))('ws');
const kToken = 'test-token-123';

let fake;
let gateway;
let base;  // http://127.0.0.1:PORT

before(async () => {
  fake = await startFakeServer(source);
  gateway = spawn(process.execPath, [path.join(source, 'client', 'web', 'gateway.js'),
                                     '--listen', '127.0.0.1:0', '--server', fake.address],
                  { env: { ...process.env, VPM_TOKEN: kToken }, stdio: ['ignore', 'pipe', 'inherit'] });
  base = await new Promise((resolve, reject) => {
    let seen = '';
    gateway.stdout.on('data', (chunk) => {
      seen += chunk;
      const m = /vpm-web listening on (http:\/\/\S+?)\/ /.exec(seen);
      if (m) resolve(m[1]);
    });
    gateway.on('exit', (code) => reject(new Error(`gateway exited ${code}: ${seen}`)));
  });
});

after(() => {
  gateway?.kill('SIGTERM');
  fake?.stop();
});

// A WebSocket client that queues what arrives: JSON messages and frames
// (header, image bytes) unpacked as the page does.
async function connect(headers = {}) {
  const ws = new WebSocket(`${base.replace('http', 'ws')}/ws`, { headers });
  const inbox = [];
  const waiters = [];
  ws.on('message', (data, isBinary) => {
    let item;
    if (isBinary) {
      const n = data.readUInt32LE(0);
      item = { type: 'frame', header: JSON.parse(data.subarray(4, 4 + n).toString()),
               image: data.subarray(4 + n) };
    } else {
      item = JSON.parse(data.toString());
    }
    inbox.push(item);
    for (const w of waiters.splice(0)) w();
  });
  await new Promise((resolve, reject) => {
    ws.on('open', resolve);
    ws.on('error', reject);
  });
  // Resolves with the first queued item matching pred (removing it).
  const next = async (pred, timeoutMs = 5000) => {
    const deadline = Date.now() + timeoutMs;
    for (;;) {
      const i = inbox.findIndex(pred);
      if (i >= 0) return inbox.splice(i, 1)[0];
      if (Date.now() > deadline) {
        throw new Error(`nothing matching ${pred} in ${JSON.stringify(inbox).slice(0, 500)}`);
      }
      await new Promise((r) => {
        waiters.push(r);
        setTimeout(r, 100);
      });
    }
  };
  const send = (m) => ws.send(JSON.stringify(m));
  return { ws, next, send };
}

const callsSince = (n) => fake.calls.slice(n);

test('Gateway_SendsTokenAndOneAffinityKeyPerTab', async () => {
  const start = fake.calls.length;
  const a = await connect();
  await a.next((m) => m.type === 'volumes');
  a.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4 } });
  await a.next((m) => m.type === 'opened');
  await a.next((m) => m.type === 'frame');
  const b = await connect();
  await b.next((m) => m.type === 'volumes');
  const calls = callsSince(start).filter((c) => c.method !== 'Interact.event');
  assert.ok(calls.length >= 5);
  for (const c of calls) assert.equal(c.authorization, `Bearer ${kToken}`, c.method);
  const keys = new Set(calls.map((c) => c.affinity));
  assert.equal(keys.size, 2, 'one x-vpm-session key per tab');
  assert.ok(![...keys].some((k) => !k), 'every call has a key');
  a.ws.close();
  b.ws.close();
});

test('Gateway_ReusesALoadedVolumeAndLoadsANewSource', async () => {
  const start = fake.calls.length;
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await t.next((m) => m.type === 'opened');
  assert.equal(opened.volume.volume_id, 'vol-1');
  assert.ok(!callsSince(start).some((c) => c.method === 'LoadVolume'));
  t.send({ type: 'open', source: 'phantom:other' });
  const second = await t.next((m) => m.type === 'opened');
  assert.equal(second.volume.source, 'phantom:other');
  assert.ok(callsSince(start).some((c) => c.method === 'LoadVolume' &&
                                          c.request.source === 'phantom:other'));
  // Opening again closes the first session.
  assert.ok(callsSince(start).some((c) => c.method === 'CloseSession' &&
                                          c.request.session_id === opened.session.session_id));
  t.ws.close();
});

test('Gateway_FramesCarryHeaderAndImage', async () => {
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4 } });
  await t.next((m) => m.type === 'opened');
  await t.next((m) => m.type === 'frame');
  t.send({ type: 'event', event: { sequence: 7, grab: { pick: true, pixel_x: 1, pixel_y: 1 } } });
  t.send({ type: 'event', event: { sequence: 8, drag: { offset_mm: { x: 1, y: 0, z: 0 } } } });
  const f = await t.next((m) => m.type === 'frame' && m.header.last_sequence === 8);
  assert.equal(f.header.max_displacement_mm, 1.5);
  assert.equal(f.header.bytes, f.image.length);
  assert.deepEqual([...f.image.subarray(0, 2)], [0xff, 0xd8]);
  t.ws.close();
});

test('Gateway_EventErrorReportsAndReopensTheStreamWithCameraAndSettings', async () => {
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4, mode: 'mip' } });
  const opened = await t.next((m) => m.type === 'opened');
  await t.next((m) => m.type === 'frame');
  const start = fake.calls.length;
  t.send({ type: 'event', event: { sequence: 3, camera: { azimuth_deg: 40 } } });
  t.send({ type: 'event', event: { sequence: 4, grab: { pick: true, pixel_x: -1, pixel_y: 0 } } });
  const error = await t.next((m) => m.type === 'error');
  assert.equal(error.what, 'Interaction');
  assert.match(error.message, /OUT_OF_RANGE: grab\.pixel: outside the last frame/);
  // The new stream names the same session and replays settings and camera
  // with the page's last sequence.
  const reopened = await t.next((m) => m.type === 'frame' && m.header.last_sequence === 4);
  assert.ok(reopened);
  const events = callsSince(start).filter((c) => c.method === 'Interact.event');
  const first = events.findIndex((c) => c.request.session_id === opened.session.session_id);
  assert.ok(first >= 0, 'no new stream on the session');
  assert.equal(events[first].request.event.settings.mode, 'RENDER_MODE_MIP');
  assert.equal(events[first].request.event.sequence, 4);
  assert.equal(events[first + 1].request.event.camera.azimuth_deg, 40);
  t.ws.close();
});

test('Gateway_ClosesTheSessionWhenTheTabGoes', async () => {
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await t.next((m) => m.type === 'opened');
  t.ws.close();
  const deadline = Date.now() + 5000;
  while (!fake.calls.some((c) => c.method === 'CloseSession' &&
                                 c.request.session_id === opened.session.session_id)) {
    assert.ok(Date.now() < deadline, 'CloseSession was not called');
    await new Promise((r) => setTimeout(r, 50));
  }
});

test('Gateway_RefusesForeignOriginsAndFilesOutsideThePage', async () => {
  await assert.rejects(connect({ Origin: 'http://elsewhere.example' }), /401/);
  const t = await connect({ Origin: base });
  t.ws.close();
  for (const [url, status] of [['/', 200], ['/app.js', 200], ['/healthz', 200],
                               ['/%2e%2e/gateway.js', 404], ['/../package.json', 404],
                               ['/.hidden', 404], ['/%', 400], ['/%zz', 400]]) {
    const r = await fetch(base + url);
    assert.equal(r.status, status, url);
  }
  assert.equal((await fetch(base + '/', { method: 'POST' })).status, 405);
});

// DNS rebinding: a page on a foreign name that resolves to the gateway sends
// that name as Host (and as Origin, so same-origin alone would pass).
test('Gateway_RefusesHostsNotAllowed', async () => {
  const port = new URL(base).port;
  const evil = `rebind.example:${port}`;
  // The status of GET `path` sent to the gateway with this Host header
  // (fetch does not let a test set Host).
  const statusWithHost = (path, host) => new Promise((resolve, reject) => {
    http.get({ host: '127.0.0.1', port, path, headers: { Host: host } },
             (res) => { res.resume(); resolve(res.statusCode); }).on('error', reject);
  });
  assert.equal(await statusWithHost('/', evil), 421);
  await assert.rejects(connect({ Host: evil, Origin: `http://${evil}` }), /Unexpected server response/);
  assert.equal(await statusWithHost('/', `localhost:${port}`), 200);
  assert.equal(await statusWithHost('/healthz', evil), 200);  // probes reach the pod by its address
});

test('Gateway_RejectsMalformedMessages', async () => {
  const t = await connect();
  t.ws.send('not json');
  assert.match((await t.next((m) => m.type === 'error')).message, /bad message/);
  t.send({ type: 'event', event: { sequence: 1, grab: { pick: true } } });
  assert.match((await t.next((m) => m.type === 'error')).message, /open a volume first/);
  t.send({ type: 'nonsense' });
  assert.match((await t.next((m) => m.type === 'error')).message, /unknown message type/);
  // JSON that is not an object, and an event that is not one: each an error
  // on this connection, which stays open.
  for (const text of ['null', '[]', '"open"', '42', '{"type":"event","event":null}',
                      '{"type":"refine","point_mm":null}']) {
    t.ws.send(text);
    await t.next((m) => m.type === 'error');
  }
  t.send({ type: 'list' });
  await t.next((m) => m.type === 'volumes');
  t.ws.close();
});

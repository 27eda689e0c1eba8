// The gateway (client/web/gateway.js) against a stand-in server
// (fake_vpm_server.mjs), through a WebSocket as the page uses it: sign-in
// (form, ?token=, cookie flags, sign-out, throttling), the signed-in user's
// token and a per-tab affinity key on every call, what the WebSocket upgrade
// refuses (no cookie, foreign or missing Origin, foreign Host), security
// headers, reuse of a loaded volume, frames in the binary format, an event
// error reopening the stream with the camera and settings replayed, the
// session closed and the mesh deleted with the tab, watching a shared
// session, malformed messages, TLS on both sides, and the case messages
// (list, open_case, rename, delete, undo; a server without --state-dir; a
// case opened afresh with its kept view).
// Usage: node --test gateway.test.mjs (SOURCE is found from this file).
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { startFakeServer } from './fake_vpm_server.mjs';
import { connect as connectTo, request, signIn, startGatewayProcess } from './gateway_client.mjs';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const kAlice = 'alice-token-123';
const kBob = 'bob-token-456';
const kViewer = 'viewer-token-789';
const sha256 = (s) => crypto.createHash('sha256').update(s).digest('hex');

let tmp;
let fake;
let gateway;
let base;  // http://127.0.0.1:PORT
let alice;  // Cookie header values
let bob;

before(async () => {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-gateway-test-'));
  fs.writeFileSync(path.join(tmp, 'users.txt'),
                   `# planners\nalice ${sha256(kAlice)}\nbob ${sha256(kBob)}\n`);
  fs.writeFileSync(path.join(tmp, 'viewer-token'), `${kViewer}\n`);
  fake = await startFakeServer(source, { users: { [kAlice]: 'alice', [kBob]: 'bob' } });
  ({ child: gateway, base } = await startGatewayProcess({ source, args: [
    '--server', fake.address, '--users', path.join(tmp, 'users.txt'),
    '--viewer-token-file', path.join(tmp, 'viewer-token')] }));
  alice = await signIn(base, kAlice);
  bob = await signIn(base, kBob);
});

after(() => {
  gateway?.kill('SIGTERM');
  fake?.stop();
  fs.rmSync(tmp, { recursive: true, force: true });
});

const connect = (options = { cookie: alice }) => connectTo(source, base, options);
const callsSince = (n) => fake.calls.slice(n);
const waitFor = async (what, pred, timeoutMs = 5000) => {
  const deadline = Date.now() + timeoutMs;
  while (!pred()) {
    assert.ok(Date.now() < deadline, what);
    await new Promise((r) => setTimeout(r, 50));
  }
};

test('Gateway_SignInSetsAStrictHttpOnlyCookie', async () => {
  const page = await request(base, '/');
  assert.equal(page.status, 303);
  assert.equal(page.headers.location, '/login');
  const form = await request(base, '/login');
  assert.equal(form.status, 200);
  assert.match(form.body, /<form id="login" method="post" action="\/login" data-link="refuse">/);
  const wrong = await request(base, '/login', {
    method: 'POST', body: 'token=nope', headers: { 'Content-Type': 'application/x-www-form-urlencoded' } });
  assert.equal(wrong.status, 401);
  assert.ok(!wrong.headers['set-cookie']);
  const ok = await request(base, '/login', {
    method: 'POST', body: `token=${kAlice}`,
    headers: { 'Content-Type': 'application/x-www-form-urlencoded' } });
  assert.equal(ok.status, 303);
  const cookie = ok.headers['set-cookie'][0];
  assert.match(cookie, /^vpm_session=[A-Za-z0-9_-]{60,}; Path=\/; HttpOnly; SameSite=Strict; Max-Age=43200$/);
  assert.ok(!cookie.includes(kAlice));
  const who = await request(base, '/whoami', { headers: { Cookie: cookie.split(';')[0] } });
  assert.deepEqual(JSON.parse(who.body), { user: 'alice' });
  assert.equal((await request(base, '/', { headers: { Cookie: cookie.split(';')[0] } })).status, 200);
  // A form posted from another site is refused before the token is looked at.
  const foreign = await request(base, '/login', {
    method: 'POST', body: `token=${kAlice}`,
    headers: { 'Content-Type': 'application/x-www-form-urlencoded', Origin: 'http://evil.example' } });
  assert.equal(foreign.status, 403);
});

// What Chromium sends with a navigation typed into the address bar.
const kTyped = { 'Sec-Fetch-Site': 'none', 'Sec-Fetch-Mode': 'navigate', 'Sec-Fetch-Dest': 'document' };

test('Gateway_TokenInTheAddressIsExchangedAtOnceAndRedirectedAway', async () => {
  const r = await request(base, `/index.html?token=${kViewer}&x=1`, { headers: kTyped });
  assert.equal(r.status, 303);
  assert.equal(r.headers.location, '/index.html?x=1');
  assert.equal(r.headers['referrer-policy'], 'no-referrer');
  const cookie = r.headers['set-cookie'][0].split(';')[0];
  const who = await request(base, '/whoami', { headers: { Cookie: cookie } });
  assert.deepEqual(JSON.parse(who.body), { user: 'viewer' });
  assert.equal((await request(base, '/?token=wrong', { headers: kTyped })).status, 401);
});

test('Gateway_TokenInTheAddressOnlyOnANavigationNotFromAnotherSite', async () => {
  const sameOrigin = { ...kTyped, 'Sec-Fetch-Site': 'same-origin' };
  const ok = await request(base, `/?token=${kViewer}`, { headers: sameOrigin });
  assert.equal(ok.status, 303);
  assert.match(ok.headers['set-cookie'][0], /^vpm_session=/);
  // Login CSRF: another site (a link, a redirect, a form, a frame, a fetch)
  // or a client that does not say where it came from.
  for (const headers of [{ ...kTyped, 'Sec-Fetch-Site': 'cross-site' },
                         { ...kTyped, 'Sec-Fetch-Site': 'same-site' },
                         { ...kTyped, 'Sec-Fetch-Mode': 'no-cors' },
                         { ...kTyped, 'Sec-Fetch-Mode': 'cors' },
                         { ...kTyped, 'Sec-Fetch-Dest': 'iframe' },
                         {}]) {
    const r = await request(base, `/?token=${kViewer}`, { headers });
    assert.equal(r.status, 303, JSON.stringify(headers));
    assert.equal(r.headers.location, '/login?link=refused');
    assert.ok(!r.headers['set-cookie'], `signed in for ${JSON.stringify(headers)}`);
  }
  assert.match((await request(base, '/login?link=refused')).body, /not from another site/);
  // The sign-in page accepts a link's fragment only on such a navigation.
  assert.match((await request(base, '/login', { headers: kTyped })).body, /data-link="accept"/);
  assert.match((await request(base, '/login', { headers: { ...kTyped, 'Sec-Fetch-Site': 'cross-site' } })).body,
               /data-link="refuse"/);
  assert.equal((await request(base, '/login.js')).status, 200);
});

test('Gateway_RedirectsStayOnThisOrigin', async () => {
  const targets = ['/.//evil.example/', '//evil.example/', '/\\evil.example/', '/\\/evil.example/',
                   '/./\\evil.example/', '/%2F%2Fevil.example/', '/%5C%5Cevil.example/',
                   '/.%2F/evil.example/', '/%2e//evil.example/', '/..//evil.example/',
                   '///evil.example/x', '/./././/evil.example/'];
  for (const target of targets) {
    const r = await request(base, `${target}?token=${kViewer}&next=1`, { headers: kTyped });
    assert.equal(r.status, 303, target);
    const location = r.headers.location;
    assert.match(location, /^\/(?![/\\])/, `${target} -> ${location}`);
    assert.equal(new URL(location, base).origin, base, `${target} -> ${location}`);
    assert.ok(!location.includes('token'), `${target} -> ${location}`);
  }
  for (const target of ['/.//evil.example/', '//evil.example/', '/\\evil.example/']) {
    const r = await request(base, target);
    if (r.headers.location) assert.equal(new URL(r.headers.location, base).origin, base, target);
  }
});

test('Gateway_SendsTheSignedInUsersTokenAndOneAffinityKeyPerTab', async () => {
  const start = fake.calls.length;
  const a = await connect({ cookie: alice });
  await a.next((m) => m.type === 'volumes');
  a.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4 } });
  await a.next((m) => m.type === 'opened');
  await a.next((m) => m.type === 'frame');
  const b = await connect({ cookie: bob });
  await b.next((m) => m.type === 'volumes');
  const calls = callsSince(start).filter((c) => c.method !== 'Interact.event');
  assert.ok(calls.length >= 5);
  const keys = new Map();  // affinity -> authorization
  for (const c of calls) {
    assert.ok(c.affinity, `${c.method} has no x-vpm-session key`);
    if (!keys.has(c.affinity)) keys.set(c.affinity, new Set());
    keys.get(c.affinity).add(c.authorization);
  }
  assert.equal(keys.size, 2, 'one x-vpm-session key per tab');
  assert.deepEqual([...keys.values()].map((s) => [...s]).sort(),
                   [[`Bearer ${kAlice}`], [`Bearer ${kBob}`]]);
  a.ws.close();
  b.ws.close();
});

test('Gateway_UpgradeNeedsCookieOriginAndHost', async () => {
  await assert.rejects(connect({ cookie: undefined }), /401/);
  await assert.rejects(connect({ cookie: 'vpm_session=forged' }), /401/);
  await assert.rejects(connect({ cookie: alice, origin: 'http://elsewhere.example' }), /403/);
  await assert.rejects(connect({ cookie: alice, origin: null }), /403/);
  const port = new URL(base).port;
  // The gateway's own origin under another allowed name is fine.
  const t = await connect({ cookie: alice, origin: `http://localhost:${port}` });
  t.ws.close();
  // DNS rebinding: a foreign name that resolves here, sent as Host and Origin.
  await assert.rejects(connect({ cookie: alice, origin: `http://rebind.example:${port}`,
                                 headers: { Host: `rebind.example:${port}` } }), /421/);
});

test('Gateway_EveryResponseCarriesSecurityHeaders', async () => {
  for (const target of ['/login', '/', '/app.js', '/no-such', '/healthz']) {
    const r = await request(base, target, { headers: { Cookie: alice } });
    assert.match(r.headers['content-security-policy'], /frame-ancestors 'none'/, target);
    assert.match(r.headers['content-security-policy'], /script-src 'self'/, target);
    assert.equal(r.headers['x-frame-options'], 'DENY', target);
    assert.equal(r.headers['x-content-type-options'], 'nosniff', target);
    assert.equal(r.headers['referrer-policy'], 'same-origin', target);
  }
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

test('Gateway_FramesCarryTheSlicesAskedForAfterTheImage', async () => {
  const t = await connect();
  const slices = [{ view: 'axial', orientation: 'SLICE_ORIENTATION_AXIAL', at_mm: 4 },
                  { view: 'coronal', orientation: 'SLICE_ORIENTATION_CORONAL',
                    window: { width: 400, level: 40 } }];
  t.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4, slices } });
  await t.next((m) => m.type === 'opened');
  const f = await t.next((m) => m.type === 'frame' && m.header.slices.length === 2);
  assert.equal(f.header.bytes, f.image.length);
  assert.deepEqual(f.header.slices.map((s) => s.view), ['axial', 'coronal']);
  // Each slice's own bytes, in order (the stand-in's JPEG comment at byte 6).
  assert.deepEqual(f.slices.map((b) => b[6]), [0, 1]);
  assert.equal(f.rest, 0);
  assert.equal(f.header.slices[0].geometry.offset_mm, 4);
  assert.deepEqual(f.header.slices[0].geometry.step_u_mm, [1, 0, 0]);
  // Four slices are refused by the gateway, naming the field.
  t.send({ type: 'event', event: { sequence: 2, settings: { slices: [...slices, ...slices] } } });
  assert.match((await t.next((m) => m.type === 'error')).message, /settings\.slices: at most 3/);
  t.send({ type: 'event', event: { sequence: 3, settings: {
    slices: [{ view: 'axial', orientation: 'SLICE_ORIENTATION_SIDEWAYS' }] } } });
  assert.match((await t.next((m) => m.type === 'error')).message, /orientation: one of/);
  t.send({ type: 'event', event: { sequence: 4, settings: {
    slices: [{ view: 'axial', orientation: 'SLICE_ORIENTATION_AXIAL', at_mm: 'x' }] } } });
  assert.match((await t.next((m) => m.type === 'error')).message, /at_mm: a finite number/);
  t.ws.close();
});

test('Gateway_UploadedTransferFunctionIsReadByTheServerAndRendersWithIt', async () => {
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded', settings: { width: 4, height: 4 } });
  await t.next((m) => m.type === 'opened');
  await t.next((m) => m.type === 'frame');
  const start = fake.calls.length;
  t.send({ type: 'tf', file_name: 'MyBone.vp', text: '1\n1\n' });
  const read = await t.next((m) => m.type === 'tf');
  assert.deepEqual([read.name, read.colors, read.opacities], ['MyBone', 2, 2]);
  const call = callsSince(start).find((c) => c.method === 'ReadTransferFunction');
  assert.equal(call.request.file_name, 'MyBone.vp');
  t.send({ type: 'event', event: { sequence: 5, settings: { width: 4, height: 4, uploaded_tf: true,
                                                             preset: 'ct-bone' } } });
  await t.next((m) => m.type === 'frame' && m.header.last_sequence === 5);
  const event = callsSince(start).filter((c) => c.method === 'Interact.event').at(-1);
  assert.equal(event.request.event.settings.render_tf.name, 'MyBone');
  assert.equal(event.request.event.settings.preset, '');  // the upload replaces the preset
  const readsBefore = fake.calls.filter((c) => c.method === 'ReadTransferFunction').length;
  t.send({ type: 'tf', file_name: 'broken.vp', text: 'bad' });
  assert.match((await t.next((m) => m.type === 'error')).message,
               /INVALID_ARGUMENT: file 'broken\.vp': line 7/);
  for (const [message, expect] of [
    [{ type: 'tf', file_name: 'a.png', text: 'x' }, /ending in \.json/],
    [{ type: 'tf', file_name: 'a.vp', text: 'x'.repeat(60001) }, /at most 60000/],
    [{ type: 'tf', file_name: 'a.vp' }, /tf: text/],
    // Issue 25's case 1: a .vp field no number is that long never reaches the server.
    [{ type: 'tf', file_name: 'x.vp', text: `1\n0\n0\n0\n0\n1\n2 ${'%'.repeat(50000)} 1\n` },
     /line 7 of the \.vp has a field of 50000 characters/],
    [{ type: 'event', event: { sequence: 6, settings: { uploaded_tf: 'yes' } } }, /uploaded_tf: true or false/],
  ]) {
    t.send(message);
    const error = await t.next((m) => m.type === 'error');
    assert.match(error.message, expect);
    assert.ok(error.message.length < 300, 'the error quotes the message');
  }
  assert.equal(fake.calls.filter((c) => c.method === 'ReadTransferFunction').length, readsBefore + 1,
               'a refused tf message reached the server');
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

test('Gateway_ClosesTheSessionAndDeletesItsMeshWhenTheTabGoes', async () => {
  const t = await connect();
  t.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await t.next((m) => m.type === 'opened');
  const start = fake.calls.length;
  t.ws.close();
  await waitFor('CloseSession then DeleteMesh', () => {
    const calls = callsSince(start);
    const closed = calls.findIndex((c) => c.method === 'CloseSession' &&
                                          c.request.session_id === opened.session.session_id);
    const deleted = calls.findIndex((c) => c.method === 'DeleteMesh' &&
                                           c.request.mesh_id === opened.mesh.mesh_id);
    return closed >= 0 && deleted > closed;
  });
});

test('Gateway_WatchesOnlySessionsSharedWithTheUser', async () => {
  const a = await connect({ cookie: alice });
  a.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await a.next((m) => m.type === 'opened');
  const b = await connect({ cookie: bob });
  b.send({ type: 'watch', session_id: opened.session.session_id });
  const refused = await b.next((m) => m.type === 'error');
  assert.equal(refused.code, 'PERMISSION_DENIED');
  fake.share(opened.session.session_id, kBob);
  b.send({ type: 'watch', session_id: opened.session.session_id });
  await b.next((m) => m.type === 'opened' && m.watching === true);
  await b.next((m) => m.type === 'frame');
  b.send({ type: 'event', event: { sequence: 1, drag: { offset_mm: { x: 1, y: 0, z: 0 } } } });
  assert.match((await b.next((m) => m.type === 'error')).message, /shared with you to watch/);
  const start = fake.calls.length;
  b.ws.close();
  await new Promise((r) => setTimeout(r, 300));
  assert.ok(!callsSince(start).some((c) => c.method === 'CloseSession'),
            'a viewer leaving closes nothing of the owner');
  a.ws.close();
});

test('Gateway_RevokedWatchStopsFramesAndTellsThePage', async () => {
  const a = await connect({ cookie: alice });
  a.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await a.next((m) => m.type === 'opened');
  const b = await connect({ cookie: bob });
  fake.share(opened.session.session_id, kBob);
  b.send({ type: 'watch', session_id: opened.session.session_id });
  await b.next((m) => m.type === 'opened' && m.watching === true);
  await b.next((m) => m.type === 'frame');
  await b.next((m) => m.type === 'frame');
  const watchesBefore = fake.calls.filter((c) => c.method === 'Watch').length;
  fake.revoke(opened.session.session_id, kBob);
  const ended = await b.next((m) => m.type === 'access_ended');
  assert.equal(ended.code, 'PERMISSION_DENIED');
  assert.equal(ended.session_id, opened.session.session_id);
  assert.match(ended.message, /no longer shared/);
  const at = b.inbox.length;
  await new Promise((r) => setTimeout(r, 300));
  assert.equal(b.inbox.slice(at).filter((m) => m.type === 'frame').length, 0,
               'frames after the revoke');
  assert.equal(fake.calls.filter((c) => c.method === 'Watch').length, watchesBefore,
               'the gateway watched again after PERMISSION_DENIED');
  b.ws.close();
  a.ws.close();
});

test('Gateway_WatchOfASessionItsOwnerClosedEndsAndIsNotReopened', async () => {
  const a = await connect({ cookie: alice });
  a.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await a.next((m) => m.type === 'opened');
  const b = await connect({ cookie: bob });
  fake.share(opened.session.session_id, kBob);
  b.send({ type: 'watch', session_id: opened.session.session_id });
  await b.next((m) => m.type === 'frame');
  const start = fake.calls.length;
  a.ws.close();  // the owner's tab goes: the gateway closes the session
  const ended = await b.next((m) => m.type === 'access_ended');
  assert.equal(ended.code, 'FAILED_PRECONDITION');
  await new Promise((r) => setTimeout(r, 300));
  assert.ok(!b.inbox.some((m) => m.type === 'session_lost'), 'the watcher was told to reopen');
  assert.ok(!callsSince(start).some((c) => ['Watch', 'GetSession', 'OpenSession'].includes(c.method) &&
                                          c.authorization === `Bearer ${kBob}`),
            'the watcher watched or opened again');
  b.ws.close();
});

test('Gateway_SignOutClosesThatBrowsersTabs', async () => {
  const cookie = await signIn(base, kBob);
  const t = await connect({ cookie });
  await t.next((m) => m.type === 'volumes');
  const out = await request(base, '/logout', { method: 'POST', headers: { Cookie: cookie } });
  assert.equal(out.status, 303);
  assert.match(out.headers['set-cookie'][0], /Max-Age=0/);
  assert.equal((await t.closed).code, 4001);
  await assert.rejects(connect({ cookie }), /401/);
  assert.equal((await request(base, '/logout', { method: 'GET' })).status, 405);
});

test('Gateway_RefusesFilesOutsideThePage', async () => {
  for (const [url, status] of [['/', 200], ['/app.js', 200], ['/healthz', 200],
                               ['/%2e%2e/gateway.js', 404], ['/../package.json', 404],
                               ['/.hidden', 404], ['/%', 400], ['/%zz', 400]]) {
    const r = await request(base, url, { headers: { Cookie: alice } });
    assert.equal(r.status, status, url);
  }
  assert.equal((await request(base, '/', { method: 'POST', headers: { Cookie: alice } })).status, 405);
});

// DNS rebinding: a page on a foreign name that resolves to the gateway sends
// that name as Host (and as Origin, so same-origin alone would pass).
test('Gateway_RefusesHostsNotAllowed', async () => {
  const port = new URL(base).port;
  const statusWithHost = (target, host) => new Promise((resolve, reject) => {
    http.get({ host: '127.0.0.1', port, path: target, headers: { Host: host, Cookie: alice } },
             (res) => { res.resume(); resolve(res.statusCode); }).on('error', reject);
  });
  assert.equal(await statusWithHost('/', `rebind.example:${port}`), 421);
  assert.equal(await statusWithHost('/login', `rebind.example:${port}`), 421);
  assert.equal(await statusWithHost('/', `localhost:${port}`), 200);
  assert.equal(await statusWithHost('/healthz', `rebind.example:${port}`), 200);  // probes
});

test('Gateway_RejectsMalformedMessages', async () => {
  const t = await connect();
  t.ws.send('not json');
  assert.match((await t.next((m) => m.type === 'error')).message, /bad message: not JSON/);
  t.send({ type: 'event', event: { sequence: 1, grab: { pick: true } } });
  assert.match((await t.next((m) => m.type === 'error')).message, /open a volume first/);
  t.send({ type: 'nonsense' });
  assert.match((await t.next((m) => m.type === 'error')).message, /unknown message type/);
  const cases = [
    ['null', /JSON object/], ['[]', /JSON object/], ['"open"', /JSON object/], ['42', /JSON object/],
    ['{"type":"event","event":null}', /event: an object/],
    ['{"type":"refine","point_mm":null}', /point_mm: an object/],
    ['{"type":"refine","point_mm":{"x":"1","y":0,"z":0}}', /point_mm\.x: a finite number/],
    ['{"type":"open"}', /one of source and volume_id/],
    ['{"type":"open","source":7}', /source: a string/],
    ['{"type":"open","source":"phantom:abdomen","settings":{"mode":"x"}}', /settings\.mode: one of/],
    ['{"type":"open","source":"phantom:abdomen","settings":{"width":1e300}}', /settings\.width: an integer/],
    ['{"type":"event","event":{"sequence":-1,"camera":{}}}', /event\.sequence: an integer/],
    ['{"type":"event","event":{"sequence":1}}', /exactly one of/],
    ['{"type":"event","event":{"camera":{"azimuth_deg":1},"drag":{}}}', /exactly one of/],
    ['{"type":"event","event":{"camera":{"nope":1}}}', /no field 'nope'/],
    ['{"type":"watch"}', /session_id required/],
    ['{"type":"delete_case","case_id":"../cases.sqlite"}', /case_id: a case id/],
    ['{"type":"rename_case","case_id":"case-1","title":""}', /title: a string of 1 to 256 bytes/],
    ['{"type":"undo","redo":"yes"}', /redo: true or false/],
  ];
  for (const [text, expect] of cases) {
    t.ws.send(text);
    assert.match((await t.next((m) => m.type === 'error')).message, expect, text);
  }
  t.send({ type: 'list' });
  await t.next((m) => m.type === 'volumes');
  t.ws.close();
});

test('Gateway_CasesOfAServerWithoutStateDirSayItKeepsNone', async () => {
  fake.keepCases(false);
  const t = await connect();
  t.send({ type: 'cases' });
  const list = await t.next((m) => m.type === 'cases');
  assert.equal(list.kept, false);
  assert.deepEqual(list.cases, []);
  assert.match(list.message, /^this server keeps no cases \(started without --state-dir\)\.$/);
  t.send({ type: 'open', source: 'phantom:loaded' });
  const opened = await t.next((m) => m.type === 'opened');
  assert.equal(opened.session.case_id ?? '', '');
  t.send({ type: 'undo' });
  const error = await t.next((m) => m.type === 'error');
  assert.equal(error.code, 'FAILED_PRECONDITION');
  assert.match(error.message, /^Undo: this server keeps no cases \(started without --state-dir\)\.$/);
  t.send({ type: 'open_case', case_id: 'case-00000001' });
  const refused = await t.next((m) => m.type === 'error');
  assert.equal(refused.case_id, 'case-00000001');
  assert.match(refused.message, /^Opening case case-00000001: this server keeps no cases/);
  t.ws.close();
});

test('Gateway_OpensUndoesRenamesAndDeletesCasesAsTheirOwner', async () => {
  fake.keepCases(true);
  const a = await connect({ cookie: alice });
  a.send({ type: 'open', source: 'phantom:loaded' });
  const first = await a.next((m) => m.type === 'opened');
  const caseId = first.session.case_id;
  assert.match(caseId, /^case-/);
  await a.next((m) => m.type === 'frame');
  a.send({ type: 'event', event: { sequence: 2, grab: { pick: true, pixel_x: 1, pixel_y: 1 } } });
  a.send({ type: 'event', event: { sequence: 3, drag: { offset_mm: { x: 1, y: 0, z: 0 } } } });
  await a.next((m) => m.type === 'frame' && m.header.last_sequence === 3);
  a.ws.close();
  await waitFor('the session closed with its tab', () => fake.calls.some(
    (c) => c.method === 'CloseSession' && c.request.session_id === first.session.session_id));

  // Another tab opens the case: OpenCase, its volume and mesh, a stream on
  // the session with the default view (no camera from the page).
  const b = await connect({ cookie: alice });
  b.send({ type: 'cases' });
  const listed = (await b.next((m) => m.type === 'cases')).cases.find((c) => c.case_id === caseId);
  assert.deepEqual([listed.owner, listed.mine, listed.events, listed.session_id], ['alice', true, 2, '']);
  const start = fake.calls.length;
  b.send({ type: 'open_case', case_id: caseId, settings: { width: 4, height: 4 }, sequence: 7 });
  const opened = await b.next((m) => m.type === 'opened');
  assert.equal(opened.session.case_id, caseId);
  assert.notEqual(opened.session.session_id, first.session.session_id);
  assert.equal(opened.volume.volume_id, 'vol-1');
  assert.equal(opened.mesh.stats.vertices, 250);
  await b.next((m) => m.type === 'frame');
  const calls = callsSince(start);
  assert.deepEqual(calls.filter((c) => ['OpenCase', 'GetVolume', 'GetMesh'].includes(c.method))
    .map((c) => c.method).sort(), ['GetMesh', 'GetVolume', 'OpenCase']);
  const events = calls.filter((c) => c.method === 'Interact.event');
  assert.equal(events[0].request.session_id, opened.session.session_id);
  assert.equal(events[0].request.event.sequence, 7);  // the page's, carried by the open
  assert.equal(events[1].request.event.camera.distance_mm, 0);

  b.send({ type: 'undo' });
  const undone = await b.next((m) => m.type === 'undone');
  assert.deepEqual([undone.changed, undone.events, undone.undone, undone.max_displacement_mm,
                    undone.redo, undone.case_id], [true, 1, 1, 1.5, false, caseId]);
  b.send({ type: 'undo', redo: true });
  const redone = await b.next((m) => m.type === 'undone');
  assert.deepEqual([redone.changed, redone.events, redone.undone, redone.redo], [true, 2, 0, true]);
  const undoCalls = callsSince(start).filter((c) => c.method === 'Undo');
  assert.deepEqual(undoCalls.map((c) => [c.request.session_id, c.request.redo]),
                   [[opened.session.session_id, false], [opened.session.session_id, true]]);

  b.send({ type: 'rename_case', case_id: caseId, title: 'Liver retraction' });
  assert.equal((await b.next((m) => m.type === 'case_renamed')).case.title, 'Liver retraction');
  await waitFor('the list after the rename', () => b.inbox.some((m) => m.type === 'cases' &&
    m.cases.some((c) => c.case_id === caseId && c.title === 'Liver retraction')));

  // Bob neither lists nor opens it: NOT_FOUND, as for a missing case.
  const bobs = await connect({ cookie: bob });
  bobs.send({ type: 'cases' });
  assert.deepEqual((await bobs.next((m) => m.type === 'cases')).cases, []);
  bobs.send({ type: 'open_case', case_id: caseId });
  const refused = await bobs.next((m) => m.type === 'error');
  assert.deepEqual([refused.code, refused.case_id], ['NOT_FOUND', caseId]);
  bobs.ws.close();

  // Deleting the case on screen stops its stream; the session is not closed
  // again (the server closed it).
  const beforeDelete = fake.calls.length;
  b.send({ type: 'delete_case', case_id: caseId });
  const deleted = await b.next((m) => m.type === 'case_deleted');
  assert.deepEqual([deleted.case_id, deleted.current], [caseId, true]);
  await waitFor('the list after the delete', () => b.inbox.some((m) => m.type === 'cases' &&
    !m.cases.some((c) => c.case_id === caseId)));
  b.send({ type: 'undo' });
  assert.match((await b.next((m) => m.type === 'error')).message, /Undo: open a volume or a case first/);
  assert.ok(!callsSince(beforeDelete).some((c) => c.method === 'CloseSession'));
  b.ws.close();
  fake.keepCases(false);
});

// A case keeps the view its stream last set; a tab that opens the case
// afresh (from the Cases panel: no camera) gets it in opened.view and its
// stream starts with it, at the page's own frame size; a tab carrying on
// with its own camera keeps its own settings.
test('Gateway_OpensACaseAfreshWithItsKeptView', async () => {
  fake.keepCases(true);
  const a = await connect({ cookie: alice });
  a.send({ type: 'open', source: 'phantom:loaded' });
  const first = await a.next((m) => m.type === 'opened');
  const caseId = first.session.case_id;
  await a.next((m) => m.type === 'frame');
  const crop = { lo_mm: { x: -10, y: -20, z: -30 }, hi_mm: { x: 10.25, y: 20, z: 30 } };
  const clip = [{ normal: { x: 1, y: 0, z: 0 }, offset_mm: 2.5 }];
  const slices = [
    { view: 'axial', orientation: 'SLICE_ORIENTATION_AXIAL', at_mm: 12.5,
      window: { width: 300, level: 50 } },
    { view: 'coronal', orientation: 'SLICE_ORIENTATION_CORONAL', at_mm: -4 }];
  a.send({ type: 'event', event: { sequence: 2, settings: {
    mode: 'dvr', preset: 'ct-bone', width: 8, height: 8, overlay: true, crop, clip, slices } } });
  await a.next((m) => m.type === 'frame' && m.header.last_sequence === 2);
  a.ws.close();
  await waitFor('the session closed with its tab', () => fake.calls.some(
    (c) => c.method === 'CloseSession' && c.request.session_id === first.session.session_id));

  const b = await connect({ cookie: alice });
  const start = fake.calls.length;
  b.send({ type: 'open_case', case_id: caseId,
           settings: { mode: 'mip', preset: 'ct-vessels', width: 4, height: 4 } });
  const opened = await b.next((m) => m.type === 'opened');
  assert.deepEqual([opened.view.mode, opened.view.preset, opened.view.view_cut],
                   ['dvr', 'ct-bone', false]);
  assert.deepEqual(opened.view.crop, crop);
  assert.deepEqual(opened.view.clip, clip);
  assert.deepEqual(opened.view.slices.map((x) => [x.view, x.orientation, x.at_mm]),
                   [['axial', 'SLICE_ORIENTATION_AXIAL', 12.5],
                    ['coronal', 'SLICE_ORIENTATION_CORONAL', -4]]);
  assert.deepEqual(opened.view.slices[0].window, { width: 300, level: 50 });
  assert.equal(opened.view.width, undefined);
  await b.next((m) => m.type === 'frame');
  const calls = callsSince(start);
  assert.ok(calls.some((c) => c.method === 'GetCase' && c.request.case_id === caseId));
  const settings = calls.find((c) => c.method === 'Interact.event').request.event.settings;
  assert.deepEqual([settings.mode, settings.preset, settings.width, settings.height, settings.overlay],
                   ['RENDER_MODE_DVR', 'ct-bone', 4, 4, false]);
  assert.deepEqual(settings.crop, crop);
  assert.deepEqual(settings.clip, clip);
  assert.deepEqual(settings.slices.map((x) => x.at_mm), [12.5, -4]);

  // Reopened with the page's camera (carrying on): the page's settings.
  const again = fake.calls.length;
  b.send({ type: 'open_case', case_id: caseId, settings: { mode: 'mip', width: 4, height: 4 },
           camera: { azimuth_deg: 10, elevation_deg: 0, distance_mm: 0 } });
  const carried = await b.next((m) => m.type === 'opened' && m !== opened);
  assert.equal(carried.view, undefined);
  await waitFor('the carried-on stream', () => callsSince(again).some(
    (c) => c.method === 'Interact.event' && c.request.event.settings));
  assert.ok(!callsSince(again).some((c) => c.method === 'GetCase'));
  assert.equal(callsSince(again).find((c) => c.method === 'Interact.event' &&
    c.request.event.settings).request.event.settings.mode, 'RENDER_MODE_MIP');
  b.ws.close();
  fake.keepCases(false);
});

test('Gateway_ClosesSessionsAKilledGatewayLeftBeforeOpeningAnother', async () => {
  const file = path.join(tmp, 'sessions.json');
  // The record a killed gateway left: alice's two sessions, one of bob's.
  fs.writeFileSync(file, JSON.stringify({ sessions: [
    { user: 'alice', id: 'ses-left-1' }, { user: 'alice', id: 'ses-left-2' },
    { user: 'bob', id: 'ses-left-3' }] }));
  const { child, base: other } = await startGatewayProcess({ source, args: [
    '--server', fake.address, '--users', path.join(tmp, 'users.txt'), '--sessions-file', file] });
  try {
    const cookie = await signIn(other, kAlice);
    const start = fake.calls.length;
    const t = await connectTo(source, other, { cookie });
    t.send({ type: 'open', source: 'phantom:loaded' });
    const opened = await t.next((m) => m.type === 'opened');
    const calls = callsSince(start).filter((c) => ['CloseSession', 'OpenSession'].includes(c.method));
    assert.deepEqual(calls.map((c) => `${c.method} ${c.request.session_id ?? ''}`).sort(),
                     ['CloseSession ses-left-1', 'CloseSession ses-left-2', 'OpenSession '].sort());
    assert.equal(calls.at(-1).method, 'OpenSession', 'opened before the leftovers were closed');
    assert.ok(calls.every((c) => c.authorization === `Bearer ${kAlice}`));
    const recorded = () => JSON.parse(fs.readFileSync(file, 'utf8')).sessions.map((x) => x.id).sort();
    assert.deepEqual(recorded(), [opened.session.session_id, 'ses-left-3'].sort());
    t.ws.close();
    await waitFor('the closed tab is still recorded', () => recorded().length === 1);
    assert.ok(!fs.readFileSync(file, 'utf8').includes(kAlice), 'a token in the record');
  } finally {
    child.kill('SIGTERM');
  }
});

test('Gateway_EachUserHasAConnectionOfTheirOwn', async () => {
  // A server that accepts TCP connections and never answers: the calls of
  // alice and bob must open two connections (grpc-js puts equal channels on
  // one unless each has its own subchannel pool), alice's second call none.
  const { VpmClient } = await import('../../client/web/lib/vpm_client.js');
  const net = await import('node:net');
  const sockets = [];
  const silent = net.createServer((s) => {
    sockets.push(s);
    s.on('error', () => {});
  });
  await new Promise((r) => silent.listen(0, '127.0.0.1', r));
  const client = new VpmClient({ address: `127.0.0.1:${silent.address().port}` });
  try {
    for (const token of [kAlice, kBob, kAlice]) client.call('ListVolumes', {}, { token }).catch(() => {});
    await waitFor('two connections', () => sockets.length >= 2, 3000);
    await new Promise((r) => setTimeout(r, 300));
    assert.equal(sockets.length, 2);
  } finally {
    client.close();
    for (const s of sockets) s.destroy();
    silent.close();
  }
});

test('Gateway_TlsOnBothSides', async () => {
  // A self-signed certificate for 127.0.0.1, for the gateway and the server.
  const key = path.join(tmp, 'tls.key');
  const cert = path.join(tmp, 'tls.pem');
  execFileSync('openssl', ['req', '-x509', '-newkey', 'ec', '-pkeyopt', 'ec_paramgen_curve:P-256',
                           '-nodes', '-days', '1', '-subj', '/CN=127.0.0.1', '-addext',
                           'subjectAltName=IP:127.0.0.1,DNS:localhost', '-keyout', key, '-out', cert],
               { stdio: 'ignore' });
  const ca = fs.readFileSync(cert);
  const tlsFake = await startFakeServer(source, { tls: { cert: ca, key: fs.readFileSync(key) } });
  const { child, base: tlsBase } = await startGatewayProcess({ source, args: [
    '--server', tlsFake.address, '--server-tls-ca', cert, '--tls-cert', cert, '--tls-key', key,
    '--users', path.join(tmp, 'users.txt')] });
  try {
    assert.match(tlsBase, /^https:/);
    const cookie = await signIn(tlsBase, kAlice, { ca });
    const r = await request(tlsBase, '/login', { ca });
    assert.match(r.headers['strict-transport-security'], /max-age=/);
    const t = await connectTo(source, tlsBase, { cookie, ca });
    t.send({ type: 'open', source: 'phantom:loaded' });
    await t.next((m) => m.type === 'opened');
    await t.next((m) => m.type === 'frame');
    assert.ok(tlsFake.calls.some((c) => c.method === 'OpenSession' &&
                                        c.authorization === `Bearer ${kAlice}`));
    t.ws.close();
    // The Secure flag under TLS.
    const form = await request(tlsBase, '/login', {
      method: 'POST', ca, body: `token=${kAlice}`,
      headers: { 'Content-Type': 'application/x-www-form-urlencoded' } });
    assert.match(form.headers['set-cookie'][0], /; Secure$/);
  } finally {
    child.kill('SIGTERM');
    tlsFake.stop();
  }
});

// Last: it locks this address out of signing in for a minute.
test('Gateway_ThrottlesFailedSignIns', async () => {
  const statuses = [];
  for (let i = 0; i < 12; ++i) {
    statuses.push((await request(base, '/login', {
      method: 'POST', body: 'token=guess', headers: { 'Content-Type': 'application/x-www-form-urlencoded' } })).status);
  }
  assert.ok(statuses.slice(0, 5).every((s) => s === 401), statuses.join(','));
  assert.equal(statuses.at(-1), 429);
  // Browsers already signed in carry on.
  const t = await connect({ cookie: alice });
  await t.next((m) => m.type === 'volumes');
  t.ws.close();
});

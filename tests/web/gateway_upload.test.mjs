// Uploads from the desktop through the gateway (POST /upload,
// lib/volume_upload.js) to the stand-in server's UploadVolume
// (fake_upload.mjs, the real server's rules): a NIfTI file reaches the
// server as the tab's user and affinity key, header first with the right
// size and SHA-256, then 1 MiB chunks, progress on the tab's WebSocket, and
// opens as a volume of the list does; DICOM files packed by the page's own
// ZIP writer arrive whole and readable (python3's zipfile, every CRC); the
// server's refusals come back in words; an upload over the cap, one without
// a sign-in, from another Origin, of a bad name or type, or a second one of
// the same user at once is refused before anything reaches the server; a
// cancelled upload (while it arrives, and while the server reads it) leaves
// no temporary file, not even an open one; and the gateway's log names no
// file.
// Usage: node --test gateway_upload.test.mjs (SOURCE is found from this file).
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

import { startFakeServer } from './fake_vpm_server.mjs';
import { connect as connectTo, signIn, startGatewayProcess } from './gateway_client.mjs';
import { readZip } from './zip_check.mjs';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const publicModule = (file) =>
  import(pathToFileURL(path.join(source, 'client/web/public', file)).href);
const { planUpload } = await publicModule('upload_files.js');
const { storeZip } = await publicModule('zip_writer.js');

const kAlice = 'alice-token-upload';
const kBob = 'bob-token-upload';
const kMiB = 1024 * 1024;
const kCapBytes = 3 * kMiB;
const sha256 = (b) => crypto.createHash('sha256').update(b).digest('hex');
// Names as patients' files are named: none may reach the gateway's log.
const kPatientNames = ['DOE^JOHN', 'SMITH^ANNA', 'ROE^RICHARD', 'MOE^MARY'];

let tmp;
let spool;  // the gateway's TMPDIR
let fake;
let gateway;
let base;
let alice;
let bob;
let gatewayLog = '';

before(async () => {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-gateway-upload-test-'));
  spool = path.join(tmp, 'spool');
  fs.mkdirSync(spool);
  fs.writeFileSync(path.join(tmp, 'users.txt'), `alice ${sha256(kAlice)}\nbob ${sha256(kBob)}\n`);
  fake = await startFakeServer(source, { users: { [kAlice]: 'alice', [kBob]: 'bob' } });
  ({ child: gateway, base } = await startGatewayProcess({
    source, stderr: 'pipe', env: { TMPDIR: spool },
    args: ['--server', fake.address, '--users', path.join(tmp, 'users.txt'),
           '--max-upload-bytes', String(kCapBytes)] }));
  gateway.stderr.on('data', (chunk) => { gatewayLog += chunk; });
  alice = await signIn(base, kAlice);
  bob = await signIn(base, kBob);
});

after(() => {
  gateway?.kill('SIGTERM');
  fake?.stop();
  fs.rmSync(tmp, { recursive: true, force: true });
});

// A tab and its hello (tab_id, max_upload_bytes).
async function tab(cookie = alice) {
  const t = await connectTo(source, base, { cookie });
  t.hello = await t.next((m) => m.type === 'hello');
  return t;
}

// POST /upload as the page sends it. Resolves with {status, body (parsed
// when JSON), req}; `partial`: only the first `partial` bytes are written
// and the request is left open (resolves with {req} at once).
function upload(body, { cookie = alice, tabId, name = 'case.nii', origin = base, headers = {},
                        length = body.length, partial = null } = {}) {
  const all = { 'Content-Type': 'application/octet-stream', 'Content-Length': String(length),
                'X-Vpm-File-Name': encodeURIComponent(name), ...headers };
  if (cookie) all.Cookie = cookie;
  if (origin) all.Origin = origin;
  if (tabId) all['X-Vpm-Tab'] = tabId;
  for (const [k, v] of Object.entries(all)) if (v === null) delete all[k];
  const url = new URL(base);
  return new Promise((resolve, reject) => {
    const req = http.request({ hostname: url.hostname, port: url.port, path: '/upload',
                               method: 'POST', headers: all }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => {
        const text = Buffer.concat(chunks).toString();
        let parsed = text;
        try {
          parsed = JSON.parse(text);
        } catch { /* a plain-text answer */ }
        resolve({ status: res.statusCode, body: parsed, req });
      });
    });
    req.on('error', partial === null ? reject : () => {});
    if (partial === null) {
      req.end(body);
    } else {
      req.write(body.subarray(0, partial));
      resolve({ req });
    }
  });
}

// The gateway's open files that are upload spools: [target, size in bytes]
// per descriptor (an unlinked one's target reads "... (deleted)").
function spoolFds() {
  const dir = `/proc/${gateway.pid}/fd`;
  return fs.readdirSync(dir).flatMap((fd) => {
    try {
      const target = fs.readlinkSync(path.join(dir, fd));
      if (!target.includes('vpm-web-upload-')) return [];
      return [[target, fs.statSync(path.join(dir, fd)).size]];
    } catch {
      return [];
    }
  });
}

const openSpools = () => spoolFds().map(([target]) => target);

// True once one spool is open and holds bytes: the gateway has made it
// (its name already removed) and is receiving into it.
const spooling = () => spoolFds().some(([, size]) => size > 0);

async function until(what, predicate, timeoutMs = 5000) {
  const deadline = Date.now() + timeoutMs;
  while (!predicate()) {
    if (Date.now() > deadline) throw new Error(`timed out waiting for ${what}`);
    await new Promise((r) => setTimeout(r, 20));
  }
}

const uploadsSince = (n) => fake.uploads.list.slice(n);

// The uploads the gateway has logged as ended. The log line follows the
// spool's closing and precedes the user's release, so once it is seen the
// user may upload again (a closed descriptor alone does not say so).
const endedUploads = () => (gatewayLog.match(/upload of \d+ bytes as \w+: /g) ?? []).length;
const untilEnded = (k) => until(`the gateway to log upload ${k} ended`, () => endedUploads() >= k);

test('GatewayUpload_NiftiGoesInChunksAsTheTabsUserAndOpens', async () => {
  const t = await tab();
  assert.equal(t.hello.max_upload_bytes, kCapBytes);
  assert.match(t.hello.tab_id, /^[A-Za-z0-9_-]{22}$/);
  const n = fake.uploads.list.length;
  const file = crypto.randomBytes(2.5 * kMiB);
  const r = await upload(file, { tabId: t.hello.tab_id, name: `${kPatientNames[0]}.NII` });
  assert.equal(r.status, 200, JSON.stringify(r.body));
  assert.equal(r.body.volume.source, `upload:${kPatientNames[0]}.nii`);
  assert.equal(r.body.volume.owner, 'alice');
  const [got] = uploadsSince(n);
  assert.deepEqual(got.header, { file_name: `${kPatientNames[0]}.nii`, total_bytes: file.length,
                                 sha256_hex: sha256(file) });
  assert.deepEqual(got.chunks, [kMiB, kMiB, kMiB / 2]);
  assert.ok(got.bytes.equals(file));
  assert.equal(got.authorization, `Bearer ${kAlice}`);
  // The tab's own key: a router sends the upload where the tab's calls go.
  const probe = fake.calls.find((c) => c.method === 'ListVolumes' && c.affinity === got.affinity);
  assert.ok(probe, 'the upload carries the tab\'s x-vpm-session key');
  const sending = await t.next((m) => m.type === 'upload_progress' && m.stage === 'sending' &&
                               m.bytes === file.length);
  assert.equal(sending.total_bytes, file.length);
  await t.next((m) => m.type === 'upload_progress' && m.stage === 'reading');
  // Opened as a volume picked from the list is.
  t.send({ type: 'open', volume_id: r.body.volume.volume_id, settings: { mode: 'dvr' } });
  const opened = await t.next((m) => m.type === 'opened');
  assert.equal(opened.volume.volume_id, r.body.volume.volume_id);
  await t.next((m) => m.type === 'frame');
  assert.deepEqual(openSpools(), []);
  assert.deepEqual(fs.readdirSync(spool), []);
  t.ws.close();
});

test('GatewayUpload_DicomFilesPackedByThePageArriveAsAReadableZip', async () => {
  const t = await tab();
  const files = [['SMITH^ANNA/SE1/IM0001', crypto.randomBytes(300000)],
                 ['SMITH^ANNA/SE1/IM0002', crypto.randomBytes(200000)],
                 ['SMITH^ANNA/SE2/IM0001', crypto.randomBytes(1000)],
                 ['SMITH^ANNA/.DS_Store', Buffer.from('junk')]];
  const plan = planUpload(files.map(([p, b]) => ({ file: new File([b], p.split('/').at(-1)), path: p })),
                          t.hello.max_upload_bytes);
  assert.deepEqual([plan.kind, plan.name], ['zip', 'SMITH^ANNA.zip']);
  const zip = Buffer.from(await (await storeZip(plan.entries)).arrayBuffer());
  assert.equal(zip.length, plan.bytes);
  const n = fake.uploads.list.length;
  const r = await upload(zip, { tabId: t.hello.tab_id, name: plan.name });
  assert.equal(r.status, 200, JSON.stringify(r.body));
  const [got] = uploadsSince(n);
  assert.equal(got.header.file_name, 'SMITH^ANNA.zip');
  const file = path.join(tmp, 'got.zip');
  fs.writeFileSync(file, got.bytes);
  const members = readZip(file);
  assert.deepEqual(members.map((m) => [m.name, m.size, m.method]),
                   [['IM0001', 300000, 0], ['IM0002', 200000, 0], ['IM0001_2', 1000, 0]]);
  for (const i of [0, 1, 2]) assert.ok(members[i].bytes.equals(files[i][1]), members[i].name);
  t.ws.close();
});

test('GatewayUpload_ServerRefusalsInWords', async () => {
  const t = await tab();
  const bad = await upload(Buffer.concat([Buffer.from('bad'), crypto.randomBytes(70000)]),
                           { tabId: t.hello.tab_id, name: `${kPatientNames[2]}.nii` });
  assert.equal(bad.status, 422);
  assert.equal(bad.body.code, 'INVALID_ARGUMENT');
  assert.match(bad.body.message, /^vpm-server cannot read ROE\^RICHARD\.nii as a volume: .*not a NIfTI-1 file/);
  const huge = await upload(crypto.randomBytes(1000), { tabId: t.hello.tab_id, name: 'huge.nrrd' });
  assert.equal(huge.body.code, 'RESOURCE_EXHAUSTED');
  assert.match(huge.body.message, /^huge\.nrrd does not fit within vpm-server's limits now: .*--max-volume-bytes/);
  fake.uploads.maxBytes = 1000;  // the server's own cap below the gateway's
  const over = await upload(crypto.randomBytes(1001), { tabId: t.hello.tab_id, name: 'a.mha' });
  fake.uploads.maxBytes = 2 ** 30;
  assert.deepEqual([over.status, over.body.code], [429, 'RESOURCE_EXHAUSTED']);
  t.ws.close();
});

test('GatewayUpload_OversizeRefusedBeforeTheServer', async () => {
  const t = await tab();
  const n = fake.uploads.list.length;
  // Declared over the cap: answered before a byte is read.
  const declared = await upload(Buffer.alloc(0), { tabId: t.hello.tab_id, length: kCapBytes + 1,
                                                   partial: 0 });
  const answered = await new Promise((resolve) => declared.req.on('response', (res) => {
    let text = '';
    res.on('data', (c) => { text += c; });
    res.on('end', () => resolve({ status: res.statusCode, body: JSON.parse(text) }));
  }));
  declared.req.destroy();
  assert.equal(answered.status, 413);
  assert.equal(answered.body.code, 'RESOURCE_EXHAUSTED');
  assert.match(answered.body.message, /case\.nii is 3145729 bytes; this gateway takes uploads of at most 3145728 bytes/);
  // No length (chunked): refused too, as its size is unknown.
  const chunked = await upload(Buffer.from('x'), { tabId: t.hello.tab_id,
                                                   headers: { 'Content-Length': null, 'Transfer-Encoding': 'chunked' } });
  assert.equal(chunked.status, 411);
  const empty = await upload(Buffer.alloc(0), { tabId: t.hello.tab_id });
  assert.deepEqual([empty.status, empty.body.code], [400, 'INVALID_ARGUMENT']);
  assert.equal(uploadsSince(n).length, 0);
  t.ws.close();
});

test('GatewayUpload_NotSignedInOrFromAnotherOriginRefused', async () => {
  const t = await tab();
  const n = fake.uploads.list.length;
  const body = crypto.randomBytes(1000);
  const anonymous = await upload(body, { cookie: null, tabId: t.hello.tab_id });
  assert.deepEqual([anonymous.status, anonymous.body.code], [401, 'UNAUTHENTICATED']);
  const forged = await upload(body, { cookie: 'vpm_session=AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA',
                                      tabId: t.hello.tab_id });
  assert.equal(forged.status, 401);
  assert.equal((await upload(body, { origin: 'http://evil.example', tabId: t.hello.tab_id })).status, 403);
  const noOrigin = await upload(body, { origin: null, tabId: t.hello.tab_id });
  assert.deepEqual([noOrigin.status, noOrigin.body.code], [403, 'PERMISSION_DENIED']);
  // A form of another site cannot send this type.
  const form = await upload(body, { tabId: t.hello.tab_id, headers: { 'Content-Type': 'text/plain' } });
  assert.equal(form.status, 415);
  // Bob may not upload through alice's tab, nor anyone without a tab.
  const bobs = await upload(body, { cookie: bob, tabId: t.hello.tab_id });
  assert.deepEqual([bobs.status, bobs.body.code], [409, 'FAILED_PRECONDITION']);
  assert.equal((await upload(body, { tabId: 'no-such-tab' })).status, 409);
  for (const name of ['a/b.nii', '..', '.hidden.nii', 'notes.txt', 'x\u0001.nii', '%E0%A4%A.nii']) {
    const r = await upload(body, { tabId: t.hello.tab_id, name,
                                   headers: name.startsWith('%') ? { 'X-Vpm-File-Name': name } : {} });
    assert.deepEqual([r.status, r.body.code], [400, 'INVALID_ARGUMENT'], name);
  }
  assert.equal(uploadsSince(n).length, 0);
  t.ws.close();
});

test('GatewayUpload_OnePerUserAtATime', async () => {
  const a = await tab(alice);
  const b = await tab(bob);
  const body = crypto.randomBytes(2 * kMiB);
  const first = await upload(body, { tabId: a.hello.tab_id, partial: kMiB });
  await until('the first upload spooling', () => openSpools().length === 1);
  const second = await upload(crypto.randomBytes(1000), { tabId: a.hello.tab_id, name: 'b.nii' });
  assert.deepEqual([second.status, second.body.code], [429, 'RESOURCE_EXHAUSTED']);
  assert.match(second.body.message, /an upload under way/);
  const bobs = await upload(crypto.randomBytes(1000), { cookie: bob, tabId: b.hello.tab_id });
  assert.equal(bobs.status, 200);
  const done = new Promise((resolve) => first.req.on('response', (res) => {
    res.resume();
    res.on('end', () => resolve(res.statusCode));
  }));
  first.req.end(body.subarray(kMiB));
  assert.equal(await done, 200);
  a.ws.close();
  b.ws.close();
});

test('GatewayUpload_CancelledLeavesNoTemporaryFile', async () => {
  const t = await tab();
  const n = fake.uploads.list.length;
  const ended = endedUploads();
  const body = crypto.randomBytes(3 * kMiB);
  // Cancelled while it arrives: the spool is open (and already unlinked:
  // nothing under TMPDIR), then closed; nothing reached the server.
  const arriving = await upload(body, { tabId: t.hello.tab_id, partial: kMiB });
  await until('the upload spooling', spooling);
  assert.equal(openSpools().length, 1);
  assert.match(openSpools()[0], /\(deleted\)$/);
  assert.deepEqual(fs.readdirSync(spool), []);
  arriving.req.destroy();
  await until('the spool closed', () => openSpools().length === 0);
  assert.equal(uploadsSince(n).length, 0);
  await untilEnded(ended + 1);

  // Cancelled while the server reads it: the server's call is cancelled
  // (the stand-in answers after readMs unless cancelled first).
  fake.uploads.readMs = 30000;
  const reading = await upload(body, { tabId: t.hello.tab_id, partial: body.length });
  await t.next((m) => m.type === 'upload_progress' && m.stage === 'reading');
  reading.req.destroy();
  await until('the server call cancelled', () => uploadsSince(n)[0]?.cancelled === true, 10000);
  fake.uploads.readMs = 0;
  await until('the spool closed', () => openSpools().length === 0);
  assert.deepEqual(fs.readdirSync(spool), []);
  await untilEnded(ended + 2);

  // The tab closing cancels its upload too; and the user may upload again.
  const orphan = await upload(body, { tabId: t.hello.tab_id, partial: kMiB });
  await until('the upload spooling', spooling);
  assert.equal(openSpools().length, 1);
  t.ws.close();
  await until('the spool closed', () => openSpools().length === 0);
  orphan.req.destroy();
  await untilEnded(ended + 3);
  const t2 = await tab();
  const again = await upload(crypto.randomBytes(1000), { tabId: t2.hello.tab_id });
  assert.equal(again.status, 200);
  t2.ws.close();
});

test('GatewayUpload_TheLogNamesNoFile', async () => {
  const t = await tab();
  const r = await upload(crypto.randomBytes(1000), { tabId: t.hello.tab_id,
                                                     name: `${kPatientNames[3]}.nrrd` });
  assert.equal(r.status, 200);
  t.ws.close();
  await new Promise((resolve) => setTimeout(resolve, 100));
  assert.match(gatewayLog, /upload of 1000 bytes as alice: OK/);
  for (const name of kPatientNames) assert.ok(!gatewayLog.includes(name.split('^')[0]), name);
});

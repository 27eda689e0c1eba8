// The gateway's Studies panel and Export button (lib/pacs_calls.js,
// lib/dicom_export_call.js) against the stand-in server
// (fake_vpm_server.mjs with fake_pacs.mjs), through a WebSocket as the page
// uses them: a server without --pacs, and one older than ListPacsEndpoints,
// said so; each user sees only the endpoints they may use; a search
// (wildcards, truncated), a study's series, the open of a CT series with
// its progress (one stage a poll, in order), then the session on it as for
// any loaded volume; the server's refusals (PERMISSION_DENIED, UNAVAILABLE
// of a PACS that is down while the server is up, INVALID_ARGUMENT for a
// dose report, RESOURCE_EXHAUSTED, NOT_FOUND) reported to the panel, and a
// server that is down said to be the server's; a cancelled load; the
// export's stages and summary, file parts dropped; malformed messages
// refused before the server; thumbnails as data URLs (or the row's error);
// the data root browsed by alice, never by bob; and no patient name or ID in
// the gateway's log.
// Usage: node --test gateway_pacs.test.mjs (SOURCE is found from this file).
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { after, before, test } from 'node:test';
import { fileURLToPath } from 'node:url';

import { kCtSeriesUid, kHugeSeriesUid, kSrSeriesUid, kStudies, kStudyUid } from './fake_pacs.mjs';
import { startFakeServer } from './fake_vpm_server.mjs';
import { connect as connectTo, signIn, startGatewayProcess } from './gateway_client.mjs';

const source = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const kAlice = 'alice-token-pacs';
const kBob = 'bob-token-pacs';
const sha256 = (s) => crypto.createHash('sha256').update(s).digest('hex');
const kEndpoints = [{ name: 'orthanc', users: ['alice'] }, { name: 'cloud', users: ['*'] },
                    { name: 'down', users: ['alice'], down: true }];
const kCtSource = `pacs:orthanc/${kStudyUid}/${kCtSeriesUid}`;

let tmp;
let fake;
let gateway;
let base;
let alice;
let bob;
let gatewayLog = '';

before(async () => {
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-gateway-pacs-test-'));
  fs.writeFileSync(path.join(tmp, 'users.txt'), `alice ${sha256(kAlice)}\nbob ${sha256(kBob)}\n`);
  fake = await startFakeServer(source, { users: { [kAlice]: 'alice', [kBob]: 'bob' } });
  ({ child: gateway, base } = await startGatewayProcess({ source, stderr: 'pipe', args: [
    '--server', fake.address, '--users', path.join(tmp, 'users.txt')] }));
  gateway.stderr.on('data', (chunk) => { gatewayLog += chunk; });
  alice = await signIn(base, kAlice);
  bob = await signIn(base, kBob);
});

after(() => {
  gateway?.kill('SIGTERM');
  fake?.stop();
  fs.rmSync(tmp, { recursive: true, force: true });
});

const connect = (cookie = alice) => connectTo(source, base, { cookie });
const callsOf = (method, since = 0) => fake.calls.slice(since).filter((c) => c.method === method);
const pacsError = (t, action) => t.next((m) => m.type === 'pacs_error' && m.action === action);

test('GatewayPacs_AServerWithoutPacsSaysSo', async () => {
  fake.setPacs([]);
  const t = await connect();
  t.send({ type: 'pacs_endpoints' });
  const listed = await t.next((m) => m.type === 'pacs_endpoints');
  assert.deepEqual(listed.endpoints, []);
  assert.match(listed.message, /No PACS endpoint you may use: this server was started without --pacs/);
  t.send({ type: 'pacs_search', endpoint: 'orthanc' });
  const refused = await pacsError(t, 'search');
  assert.equal(refused.code, 'FAILED_PRECONDITION');
  assert.equal(refused.message, 'Searching orthanc: this server has no PACS (started without --pacs).');
  fake.pacs.older = true;
  t.send({ type: 'pacs_endpoints' });
  const older = await t.next((m) => m.type === 'pacs_endpoints');
  fake.pacs.older = false;
  assert.deepEqual(older.endpoints, []);
  assert.match(older.message, /does not list PACS endpoints \(an older version\)/);
  t.ws.close();
});

test('GatewayPacs_EachUserSeesTheEndpointsTheyMayUse', async () => {
  fake.setPacs(kEndpoints);
  const a = await connect(alice);
  a.send({ type: 'pacs_endpoints' });
  assert.deepEqual((await a.next((m) => m.type === 'pacs_endpoints')).endpoints,
                   ['orthanc', 'cloud', 'down']);
  const b = await connect(bob);
  b.send({ type: 'pacs_endpoints' });
  const bobs = await b.next((m) => m.type === 'pacs_endpoints');
  assert.deepEqual([bobs.endpoints, bobs.message], [['cloud'], '']);
  b.send({ type: 'pacs_search', endpoint: 'orthanc', patient_name: 'DOE*' });
  const refused = await pacsError(b, 'search');
  assert.equal(refused.code, 'PERMISSION_DENIED');
  assert.match(refused.message, /^Searching orthanc: not allowed: no PACS endpoint 'orthanc' that you may use\./);
  assert.equal(refused.endpoint, 'orthanc');
  assert.equal(callsOf('SearchStudies').at(-1).authorization, `Bearer ${kBob}`);
  a.ws.close();
  b.ws.close();
});

test('GatewayPacs_SearchListSeriesOpenWithProgressAndExport', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  const start = fake.calls.length;
  t.send({ type: 'pacs_search', endpoint: 'orthanc', patient_name: 'DOE^J*', study_date: '20240101-',
           modality: 'CT' });
  const found = await t.next((m) => m.type === 'pacs_studies');
  assert.deepEqual([found.endpoint, found.truncated, found.studies.length], ['orthanc', false, 1]);
  const { series, ...study } = kStudies[0];
  assert.deepEqual(found.studies[0], study);
  const searched = callsOf('SearchStudies', start)[0];
  assert.deepEqual([searched.request.patient_name, searched.request.study_date, searched.request.modality,
                    searched.authorization], ['DOE^J*', '20240101-', 'CT', `Bearer ${kAlice}`]);

  t.send({ type: 'pacs_series', endpoint: 'orthanc', study_uid: kStudyUid });
  const listed = await t.next((m) => m.type === 'pacs_series');
  assert.equal(listed.study_uid, kStudyUid);
  assert.deepEqual(listed.series.map((s) => [s.series_number, s.modality, s.description, s.body_part,
                                             s.instance_count]),
                   [[2, 'CT', 'Abdomen 1.0', 'ABDOMEN', 112], [999, 'SR', 'Dose report', '', 1],
                    [3, 'CT', 'Thin slices', 'ABDOMEN', 5000]]);
  assert.equal(listed.series[0].source, kCtSource);

  t.send({ type: 'pacs_open', source: kCtSource });
  const loaded = await t.next((m) => m.type === 'pacs_loaded', 10000);
  assert.equal(loaded.volume.source, kCtSource);
  // One stage a poll (the stand-in moves on when polled), each sent once.
  const progress = t.inbox.filter((m) => m.type === 'pacs_progress');
  assert.deepEqual(progress.slice(0, 5).map((m) => `${m.stage} ${m.fraction}`),
                   ['queued 0', 'retrieving 0.2', 'retrieving 0.6', 'reading 0.8', 'uploading 0.95']);
  assert.ok(progress.length <= 6 && progress.every((m) => m.source === kCtSource));
  const [loadCall] = callsOf('LoadVolume', start);
  assert.match(loadCall.request.progress_id, /^[0-9a-f-]{36}$/);
  assert.ok(callsOf('GetLoadProgress', start).every((c) =>
    c.request.progress_id === loadCall.request.progress_id));

  // The page opens it as any loaded volume.
  t.send({ type: 'open', volume_id: loaded.volume.volume_id, settings: { width: 4, height: 4 } });
  const opened = await t.next((m) => m.type === 'opened');
  assert.equal(opened.volume.source, kCtSource);
  await t.next((m) => m.type === 'frame');

  const exportStart = fake.calls.length;
  t.send({ type: 'export_dicom', endpoint: 'orthanc', series_description: 'after retraction' });
  const exported = await t.next((m) => m.type === 'exported', 10000);
  assert.deepEqual(exported.summary, {
    study_uid: kStudyUid, derived_series_uid: '2.25.100', capture_series_uid: '2.25.101',
    instances: 113, endpoint: 'orthanc', series_description: 'after retraction',
    max_displacement_mm: 1.5, bytes: 4 * 1024 * 1024 });
  assert.equal(exported.dropped_files, 0);
  const exportStages = t.inbox.filter((m) => m.type === 'export_progress').map((m) => m.stage);
  assert.deepEqual(exportStages, ['starting', 'warping', 'writing', 'sending']);
  const [exportCall] = callsOf('ExportDicom', exportStart);
  assert.deepEqual(exportCall.request, { session_id: opened.session.session_id, endpoint: 'orthanc',
                                         series_description: 'after retraction' });
  t.ws.close();
});

test('GatewayPacs_ATruncatedSearchSaysSo', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  t.send({ type: 'pacs_search', endpoint: 'cloud', patient_name: '*', limit: 1 });
  const found = await t.next((m) => m.type === 'pacs_studies');
  assert.deepEqual([found.studies.length, found.truncated], [1, true]);
  t.ws.close();
});

test('GatewayPacs_RefusalsOfTheServerReachThePanel', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  t.send({ type: 'pacs_open', source: `pacs:orthanc/${kStudyUid}/${kSrSeriesUid}` });
  const sr = await pacsError(t, 'open');
  assert.equal(sr.code, 'INVALID_ARGUMENT');
  assert.match(sr.message, new RegExp(`^Opening ${kSrSeriesUid}: series ${kSrSeriesUid} holds no images$`));
  t.send({ type: 'pacs_open', source: `pacs:orthanc/${kStudyUid}/${kHugeSeriesUid}` });
  const huge = await pacsError(t, 'open');
  assert.equal(huge.code, 'RESOURCE_EXHAUSTED');
  assert.match(huge.message, /too large for the server/);
  // A PACS that is down while vpm-server is up: the panel says so, and the
  // page's server state stays up.
  t.send({ type: 'pacs_search', endpoint: 'down' });
  const down = await pacsError(t, 'search');
  assert.equal(down.code, 'UNAVAILABLE');
  assert.match(down.message, /^Searching down: the PACS is not reachable \(PACS 'down': .*\)\. vpm-server is up/);
  assert.ok(!t.inbox.some((m) => m.type === 'server' && m.up === false));
  t.send({ type: 'pacs_series', endpoint: 'orthanc', study_uid: '1.2.3' });
  const missing = await pacsError(t, 'series');
  assert.deepEqual([missing.code, missing.study_uid], ['NOT_FOUND', '1.2.3']);
  t.ws.close();
});

test('GatewayPacs_ACancelledLoadStopsOnTheServer', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  const cancelled = fake.pacs.cancelledLoads;
  t.send({ type: 'pacs_open', source: kCtSource });
  await t.next((m) => m.type === 'pacs_progress' && m.stage !== 'queued');
  t.send({ type: 'pacs_cancel' });
  const error = await pacsError(t, 'open');
  assert.equal(error.code, 'CANCELLED');
  assert.equal(error.source, kCtSource);
  const deadline = Date.now() + 2000;
  while (fake.pacs.cancelledLoads === cancelled && Date.now() < deadline) {
    await new Promise((r) => setTimeout(r, 20));
  }
  assert.equal(fake.pacs.cancelledLoads, cancelled + 1);
  await new Promise((r) => setTimeout(r, 300));
  assert.ok(!t.inbox.some((m) => m.type === 'pacs_loaded'));
  t.ws.close();
});

test('GatewayPacs_ExportDropsFilesAndNeedsASession', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  t.send({ type: 'export_dicom', endpoint: 'orthanc' });
  assert.match((await pacsError(t, 'export')).message, /^Exporting to orthanc: open a PACS series first\.$/);
  t.send({ type: 'pacs_open', source: kCtSource });
  const loaded = await t.next((m) => m.type === 'pacs_loaded', 10000);
  t.send({ type: 'open', volume_id: loaded.volume.volume_id });
  await t.next((m) => m.type === 'opened');
  t.send({ type: 'export_dicom', endpoint: 'orthanc', series_description: 'with files' });
  t.send({ type: 'export_dicom', endpoint: 'orthanc' });
  assert.match((await pacsError(t, 'export')).message, /an export of this tab is under way/);
  const exported = await t.next((m) => m.type === 'exported', 10000);
  assert.equal(exported.dropped_files, 1);
  assert.ok(!t.inbox.some((m) => m.type !== 'frame' && /derived\/000001|"data"/.test(JSON.stringify(m))),
            'a file part reached the page');
  t.send({ type: 'export_dicom', endpoint: 'cloud' });
  assert.equal((await t.next((m) => m.type === 'exported', 10000)).summary.endpoint, 'cloud');
  // Bob may not export to orthanc.
  const b = await connect(bob);
  b.send({ type: 'open', source: 'phantom:loaded' });
  await b.next((m) => m.type === 'opened');
  b.send({ type: 'export_dicom', endpoint: 'orthanc' });
  const refused = await pacsError(b, 'export');
  assert.equal(refused.code, 'PERMISSION_DENIED');
  t.ws.close();
  b.ws.close();
});

test('GatewayPacs_MalformedMessagesNeverReachTheServer', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  const start = fake.calls.length;
  for (const [message, expect] of [
    [{ type: 'pacs_search' }, /endpoint: a PACS endpoint name/],
    [{ type: 'pacs_search', endpoint: 'orthanc', patient_name: `DOE^${'J'.repeat(80)}` },
     /patient_name: a string of at most 64 bytes/],
    [{ type: 'pacs_search', endpoint: 'orthanc', study_date: '2024' }, /study_date: YYYYMMDD/],
    [{ type: 'pacs_search', endpoint: 'orthanc', where: 'x' }, /no field 'where'/],
    [{ type: 'pacs_series', endpoint: 'orthanc', study_uid: '../x' }, /study_uid: a DICOM UID/],
    [{ type: 'pacs_open', source: 'phantom:abdomen' }, /source: pacs:ENDPOINT/],
    [{ type: 'export_dicom', endpoint: '' }, /endpoint: a PACS endpoint name/],
    [{ type: 'export_dicom', endpoint: 'orthanc', series_description: 'x'.repeat(65) },
     /series_description: a string of at most 64/],
  ]) {
    t.send(message);
    const error = await t.next((m) => m.type === 'error');
    assert.match(error.message, /^bad message: /);
    assert.match(error.message, expect, JSON.stringify(message));
    assert.ok(!error.message.includes('DOE'), 'a refused value was quoted');
  }
  assert.deepEqual(fake.calls.slice(start).filter((c) => /Pacs|Studies|Series|Load|Export/.test(c.method)),
                   []);
  t.ws.close();
});

test('GatewayPacs_AServerThatIsDownIsNotBlamedOnThePacs', async () => {
  // A gateway whose server port is closed: the search's UNAVAILABLE is the
  // server's (ListVolumes fails too), and the page's server state says so.
  const net = await import('node:net');
  const closed = net.createServer();
  await new Promise((r) => closed.listen(0, '127.0.0.1', r));
  const port = closed.address().port;
  await new Promise((r) => closed.close(r));
  const { child, base: other } = await startGatewayProcess({ source, stderr: 'ignore', args: [
    '--server', `127.0.0.1:${port}`, '--users', path.join(tmp, 'users.txt')] });
  try {
    const t = await connectTo(source, other, { cookie: await signIn(other, kAlice) });
    t.send({ type: 'pacs_search', endpoint: 'orthanc', patient_name: 'DOE*' });
    const error = await pacsError(t, 'search');
    assert.equal(error.code, 'UNAVAILABLE');
    assert.match(error.message, new RegExp(`^Searching orthanc: vpm-server at 127\\.0\\.0\\.1:${port} is not reachable`));
    await t.next((m) => m.type === 'server' && m.up === false);
    t.ws.close();
  } finally {
    child.kill('SIGTERM');
  }
});

test('GatewayPacs_ThumbnailsComeAsDataUrlsOrAsTheRowsError', async () => {
  fake.setPacs(kEndpoints);
  const t = await connect();
  const start = fake.calls.length;
  const ask = (seriesUid) => t.send({ type: 'pacs_thumbnail', endpoint: 'orthanc',
                                      study_uid: kStudyUid, series_uid: seriesUid });
  ask(kCtSeriesUid);
  ask(kSrSeriesUid);
  const ct = await t.next((m) => m.type === 'pacs_thumbnail' && m.series_uid === kCtSeriesUid);
  assert.match(ct.data_url, /^data:image\/png;base64,iVBORw0KGgo/);
  assert.deepEqual([ct.endpoint, ct.study_uid, ct.width, ct.height], ['orthanc', kStudyUid, 1, 1]);
  const sr = await t.next((m) => m.type === 'pacs_thumbnail' && m.series_uid === kSrSeriesUid);
  assert.equal(sr.data_url, undefined);
  assert.equal(sr.code, 'INVALID_ARGUMENT');
  assert.match(sr.message, /holds no image/);
  const called = callsOf('GetSeriesThumbnail', start);
  assert.deepEqual(called.map((c) => c.request.size_px), [96, 96]);
  assert.equal(called[0].authorization, `Bearer ${kAlice}`);
  // Checked before the server: a bad UID never reaches it.
  t.send({ type: 'pacs_thumbnail', endpoint: 'orthanc', study_uid: kStudyUid, series_uid: '1.x' });
  const bad = await t.next((m) => m.type === 'error' && m.what === 'message');
  assert.match(bad.message, /series_uid: a DICOM UID/);
  assert.equal(callsOf('GetSeriesThumbnail', start).length, 2);
  // Bob may not use the endpoint: his row says so, the panel is untouched.
  const b = await connect(bob);
  b.send({ type: 'pacs_thumbnail', endpoint: 'orthanc', study_uid: kStudyUid, series_uid: kCtSeriesUid });
  const refused = await b.next((m) => m.type === 'pacs_thumbnail');
  assert.equal(refused.code, 'PERMISSION_DENIED');
  t.ws.close();
  b.ws.close();
});

test('GatewayDataRoot_AliceBrowsesBobNeverSeesTheSection', async () => {
  const t = await connect();
  t.send({ type: 'data_ls', path: '' });
  const root = await t.next((m) => m.type === 'data_listing');
  assert.deepEqual(root.entries.map((e) => [e.name, e.kind, e.source]),
                   [['ct', 'DICOM_FOLDER', 'ct'], ['kidney.nii.gz', 'VOLUME_FILE', 'kidney.nii.gz']]);
  t.send({ type: 'data_ls', path: 'cases' });
  const cases = await t.next((m) => m.type === 'data_listing');
  assert.deepEqual([cases.path, cases.entries[1].source, cases.entries[1].size_bytes],
                   ['cases', 'cases/kidney.nii.gz', 123456]);
  t.send({ type: 'data_ls', path: 'missing' });
  const missing = await t.next((m) => m.type === 'data_error');
  assert.deepEqual([missing.code, missing.allowed], ['NOT_FOUND', true]);
  t.send({ type: 'data_ls', path: '../etc' });
  const bad = await t.next((m) => m.type === 'error' && m.what === 'message');
  assert.match(bad.message, /path: a folder relative to the data root/);
  assert.equal(callsOf('ListDataRoot').filter((c) => c.request.path === '../etc').length, 0);
  const b = await connect(bob);
  b.send({ type: 'data_ls', path: '' });
  const denied = await b.next((m) => m.type === 'data_error');
  assert.deepEqual([denied.code, denied.allowed], ['PERMISSION_DENIED', false]);
  t.ws.close();
  b.ws.close();
});

// Last: what the gateway logged over all the tests above.
test('GatewayPacs_NoPatientNameOrIdInTheGatewayLog', async () => {
  await new Promise((r) => setTimeout(r, 200));
  assert.match(gatewayLog, /PACS search on orthanc: PERMISSION_DENIED/);
  for (const s of kStudies) {
    for (const value of [s.patient_name, s.patient_id, s.patient_birth_date, ...s.patient_name.split('^')]) {
      assert.ok(!gatewayLog.includes(value), `the gateway logged '${value}'`);
    }
  }
});

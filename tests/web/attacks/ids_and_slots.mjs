// Issue 25, points 3 and 8, over gRPC as any client could (the gateway
// carries neither uploads nor made-up ids):
//
// runIds: volume, mesh and session ids are random (vol-TAG-<32 hex>, no
// counter to read how many exist), and bob gets exactly a missing id's
// answer (NOT_FOUND, the same message) for alice's upload, her session and
// her load's progress id.
//
// runVolumeSlots: the case 4 through sessions, on a server of its
// own (--max-volumes 4 --max-volumes-per-user 2 --max-sessions-per-user 8):
// alice opens sessions on four phantoms; only two are taken, and bob's
// LoadVolume and UploadVolume are served (before, her four sessions held
// every slot and bob got "the server's volumes are all in use").
import assert from 'node:assert/strict';
import crypto from 'node:crypto';
import fs from 'node:fs';
import path from 'node:path';

import { randomToken, startServer, stopChild, writeUsersFile } from '../harness.mjs';
import { VpmClient, statusName } from '../../../client/web/lib/vpm_client.js';

const kIdPattern = (kind) => new RegExp(`^${kind}-[0-9a-f]{8}-[0-9a-f]{32}$`);

// The gRPC status of `promise`: 'OK' or {code, details}.
async function outcome(promise) {
  try {
    await promise;
    return 'OK';
  } catch (e) {
    return { code: statusName(e.code), details: e.details };
  }
}

// UploadVolume of a small NIfTI (the kidney mask of tests/data) as `token`.
function upload(client, token, source) {
  const bytes = fs.readFileSync(path.join(source, 'tests', 'data', 'ct-abdomen-kidney',
                                          'left_kidney_mask.nii.gz'));
  return new Promise((resolve, reject) => {
    const call = client.stub({ token }).UploadVolume(client.metadata({ token }),
                                                     (err, info) => (err ? reject(err) : resolve(info)));
    call.write({ header: { file_name: 'mask.nii.gz', total_bytes: bytes.length,
                           sha256_hex: crypto.createHash('sha256').update(bytes).digest('hex') } });
    for (let at = 0; at < bytes.length; at += 1 << 20) call.write({ chunk: bytes.subarray(at, at + (1 << 20)) });
    call.end();
  });
}

export async function runIds(ctx) {
  const { grpc, tokens } = ctx;
  const alice = { token: tokens.alice };
  const bob = { token: tokens.bob };
  const madeUp = (kind) => `${kind}-${'0'.repeat(8)}-${'0'.repeat(32)}`;
  const uploaded = await upload(grpc, tokens.alice, ctx.source);
  const phantom = await grpc.call('LoadVolume', { source: 'phantom:abdomen?size=24',
                                                  progress_id: 'alices-load' }, alice);
  const mesh = await grpc.call('BuildMesh', { volume_id: phantom.volume_id }, alice);
  const session = await grpc.call('OpenSession', { mesh_id: mesh.mesh_id }, alice);
  const ids = { upload: uploaded.volume_id, volume: phantom.volume_id, mesh: mesh.mesh_id,
                session: session.session_id };
  // Bob's answer for alice's thing, and for a made-up id of the same kind.
  const pairs = {
    upload: [() => grpc.call('GetVolume', { volume_id: uploaded.volume_id }, bob),
             () => grpc.call('GetVolume', { volume_id: madeUp('vol') }, bob)],
    mesh_on_upload: [() => grpc.call('BuildMesh', { volume_id: uploaded.volume_id }, bob),
                     () => grpc.call('BuildMesh', { volume_id: madeUp('vol') }, bob)],
    session: [() => grpc.call('GetSession', { session_id: session.session_id }, bob),
              () => grpc.call('GetSession', { session_id: madeUp('ses') }, bob)],
    progress_id: [() => grpc.call('GetLoadProgress', { progress_id: 'alices-load' }, bob),
                  () => grpc.call('GetLoadProgress', { progress_id: 'never-used' }, bob)],
  };
  const answers = {};
  for (const [what, [theirs, missing]] of Object.entries(pairs)) {
    answers[what] = { alices: await outcome(theirs()), made_up: await outcome(missing()) };
  }
  ctx.step(`ids: ${JSON.stringify({ ids, answers })}`);
  await grpc.call('CloseSession', { session_id: session.session_id }, alice);
  await grpc.call('DeleteVolume', { volume_id: uploaded.volume_id }, alice);
  assert.match(ids.upload, kIdPattern('vol'));
  assert.match(ids.volume, kIdPattern('vol'));
  assert.match(ids.mesh, kIdPattern('mesh'));
  assert.match(ids.session, kIdPattern('ses'));
  for (const [what, { alices, made_up: madeUpAnswer }] of Object.entries(answers)) {
    assert.equal(alices.code, 'NOT_FOUND', `${what}: ${JSON.stringify(alices)}`);
    // The same text; a progress id is the caller's own and is quoted.
    const expected = what === 'progress_id'
      ? { ...madeUpAnswer, details: madeUpAnswer.details.replace('never-used', 'alices-load') }
      : madeUpAnswer;
    assert.deepEqual(alices, expected, `${what}: alice's answers unlike a missing one's`);
  }
  return { ids: Object.values(ids).map((id) => id.replace(/[0-9a-f]{32}$/, 'R')),
           bob_got: Object.fromEntries(Object.entries(answers).map(([k, v]) => [k, v.alices.code])) };
}

export async function runVolumeSlots(ctx) {
  const tokens = { alice: randomToken(), bob: randomToken() };
  const usersFile = writeUsersFile(path.join(ctx.out, 'attacker_slots_users.txt'), tokens);
  const server = await startServer({
    build: ctx.build, out: ctx.out, token: randomToken(), logName: 'attacker_slots_server.log',
    args: ['--users', usersFile, '--max-volumes', '4', '--max-volumes-per-user', '2',
           '--max-sessions', '16', '--max-sessions-per-user', '8'] });
  const client = new VpmClient({ address: server.address });
  try {
    const alice = { token: tokens.alice };
    const bob = { token: tokens.bob };
    const opened = [];
    for (let i = 0; i < 4; ++i) {
      const volume = await client.call('LoadVolume', { source: `phantom:abdomen?size=${24 + i}` }, alice);
      opened.push(await outcome(client.call('OpenSession', { volume_id: volume.volume_id }, alice)));
    }
    const bobsLoad = await outcome(client.call('LoadVolume', { source: 'phantom:abdomen?size=32' }, bob));
    const bobsUpload = await outcome(upload(client, tokens.bob, ctx.source));
    const figures = { alice_sessions: opened.map((o) => (o === 'OK' ? 'OK' : o.code)),
                      bob_load: bobsLoad === 'OK' ? 'OK' : bobsLoad, bob_upload: bobsUpload === 'OK' ? 'OK' : bobsUpload };
    ctx.step(`volume_slots: ${JSON.stringify({ ...figures, alice: opened })}`);
    assert.equal(bobsLoad, 'OK', `bob's LoadVolume: ${JSON.stringify(bobsLoad)}`);
    assert.equal(bobsUpload, 'OK', `bob's UploadVolume: ${JSON.stringify(bobsUpload)}`);
    assert.deepEqual(figures.alice_sessions, ['OK', 'OK', 'RESOURCE_EXHAUSTED', 'RESOURCE_EXHAUSTED']);
    return figures;
  } finally {
    client.close();
    await stopChild(server.child);
  }
}

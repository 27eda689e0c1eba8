// Session affinity through HAProxy (docker/haproxy.cfg) over three
// vpm-server replicas on loopback: every call of one `x-vpm-session` key
// reaches the replica that holds the key's volume and session.
//  1. Nine keys, each through the balancer with the `vpm` CLI: LoadVolume of
//     the shared data root's NIfTI, OpenSession, four Manipulate (grab, two
//     drags, release), SetCamera, Render, and a `vpm play` of a short script
//     on the Interact stream. Ids carry their replica's tag, so a call that
//     reached another replica would fail NOT_FOUND: every call succeeds, each
//     session is held by the replica its id names and by no other, the keys
//     spread over more than one replica, and each replica's Manipulate count
//     (its own metrics) is four times the keys it holds.
//  2. The same calls through a copy of the config balancing round robin
//     instead of hashing the header: some call must fail, or this test could
//     not see a routing fault.
// Usage: node affinity_test.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';

import { runScenario } from '../web/harness.mjs';
import {
  makeDataRoot, metric, replicaOf, sessionsByReplica, startBalancer, startReplicas, testPaths,
  vpm, vpmOk,
} from './cluster.mjs';

const { build, source, out } = testPaths(process.argv, 'affinity');
const step = (text) => console.log(`balancer_affinity: ${text}`);
const kKeys = 9;

// The calls of one workspace, all with `key`; returns {volume, session} ids.
async function workspace(balancer, key, volumeSource) {
  const g = ['--server', balancer.address, '--session-key', key];
  const volume = await vpmOk(build, [...g, 'volume', 'load', volumeSource]);
  const session = await vpmOk(build, [...g, 'session', 'open', '--volume-id', volume.volume_id]);
  const s = ['--session', session.session_id];
  // The middle of the volume's world box (LPS mm, the API's frame).
  const [lo, hi] = volume.box_lps_mm;
  const centre = lo.map((l, i) => String((l + hi[i]) / 2));
  await vpmOk(build, [...g, 'manipulate', ...s, '--grab', ...centre]);
  await vpmOk(build, [...g, 'manipulate', ...s, '--drag', '0', '0', '5']);
  await vpmOk(build, [...g, 'manipulate', ...s, '--drag', '0', '0', '10']);
  await vpmOk(build, [...g, 'manipulate', ...s, '--release']);
  await vpmOk(build, [...g, 'set-camera', ...s, '30', '10']);
  await vpmOk(build, [...g, 'snapshot', ...s, '--size', '64', '64',
                      '--out', path.join(out, `${key}.png`)]);
  return { volume: volume.volume_id, session: session.session_id };
}

async function main() {
  const { dataRoot, source: volumeSource } = await makeDataRoot(build, out);
  const replicas = await startReplicas({ build, out, n: 3, dataRoot, source: volumeSource });
  const balancer = await startBalancer({ source, out, replicas });
  step(`3 replicas (${replicas.map((r) => `${r.name}=${r.tag}`).join(', ')}) behind HAProxy at ` +
       `${balancer.address}`);
  const manipulateBefore = await Promise.all(replicas.map(
    (r) => metric(r, 'vpm_requests_total', { method: 'Manipulate', code: 'OK' })));

  // 1. Affinity.
  const held = {};  // key -> replica
  for (let i = 0; i < kKeys; ++i) {
    const key = `key-affinity-${i}`;
    const ids = await workspace(balancer, key, volumeSource);
    const replica = replicaOf(replicas, ids.volume);
    assert.equal(replicaOf(replicas, ids.session), replica,
                 `${key}: OpenSession reached another replica than LoadVolume`);
    held[key] = { replica, session: ids.session };
  }
  const sessions = await sessionsByReplica(build, replicas);
  for (const [key, { replica, session }] of Object.entries(held)) {
    for (const r of replicas) {
      assert.equal(sessions[r.name].includes(session), r === replica,
                   `${key}: session ${session} on ${r.name}: ${sessions[r.name]}`);
    }
  }
  const used = new Set(Object.values(held).map((h) => h.replica.name));
  step(`${kKeys} keys: ${replicas.map((r) => `${r.name} ${
    Object.values(held).filter((h) => h.replica === r).length}`).join(', ')}`);
  assert.ok(used.size >= 2, 'every key hashed to one replica: no balancing');
  for (const [i, r] of replicas.entries()) {
    const manipulated = await metric(r, 'vpm_requests_total', { method: 'Manipulate', code: 'OK' });
    const keys = Object.values(held).filter((h) => h.replica === r).length;
    assert.equal(manipulated - manipulateBefore[i], 4 * keys,
                 `${r.name}: ${manipulated - manipulateBefore[i]} Manipulate calls for ${keys} keys`);
  }
  step('every LoadVolume, OpenSession, Manipulate, SetCamera and Render met its session');

  // The Interact stream: `vpm play` opens its session where its key goes.
  const script = path.join(out, 'short.json');
  fs.writeFileSync(script, JSON.stringify({
    volume: volumeSource, settings: { width: 64, height: 64 }, interval_ms: 20,
    steps: [{ orbit: { to_azimuth_deg: 40, steps: 8 } }] }));
  for (const key of Object.keys(held).slice(0, 3)) {
    const report = path.join(out, `${key}.play.json`);
    await vpmOk(build, ['--server', balancer.address, '--session-key', key, 'play', script,
                        '--report', report]);
    const played = JSON.parse(fs.readFileSync(report, 'utf8'));
    assert.ok(played.frames > 0, `${key}: no frames`);
    assert.equal(replicaOf(replicas, played.session_id), held[key].replica,
                 `${key}: play's session ${played.session_id} is not on ${held[key].replica.name}`);
  }
  step('vpm play: each Interact stream ran on its key\'s replica');

  // 2. The same calls balanced round robin must go wrong somewhere.
  const roundRobin = path.join(out, 'roundrobin');
  fs.mkdirSync(roundRobin, { recursive: true });
  const shipped = fs.readFileSync(path.join(source, 'docker', 'haproxy.cfg'), 'utf8');
  assert.match(shipped, /^\s*balance hdr\(x-vpm-session\)$/m);
  const copy = path.join(roundRobin, 'docker');
  fs.mkdirSync(copy, { recursive: true });
  fs.writeFileSync(path.join(copy, 'haproxy.cfg'),
                   shipped.replace(/^(\s*)balance hdr\(x-vpm-session\)$/m, '$1balance roundrobin'));
  const wrong = await startBalancer({ source: roundRobin, out: roundRobin, replicas });
  let failures = 0;
  for (let i = 0; i < 3; ++i) {
    const g = ['--server', wrong.address, '--session-key', `key-rr-${i}`];
    const volume = await vpmOk(build, [...g, 'volume', 'load', volumeSource]);
    const open = await vpm(build, [...g, 'session', 'open', '--volume-id', volume.volume_id]);
    if (open.code !== 0) ++failures;
  }
  step(`round robin instead of the header hash: ${failures} of 3 OpenSession calls missed their volume`);
  assert.ok(failures > 0, 'round robin never misrouted: the affinity check could not fail');
}

runScenario('balancer_affinity', main);

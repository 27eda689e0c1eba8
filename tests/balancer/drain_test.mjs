// A replica stopped the way Docker and Kubernetes stop it (SIGTERM) behind
// HAProxy (docker/haproxy.cfg), with vpm-server's --drain-s as compose and
// the manifests give it:
//  - HAProxy's health check (grpc.health.v1 over HTTP/2) sees NOT_SERVING
//    and takes the replica out of rotation while it still runs: `vpm health`
//    on it says NOT_SERVING, and the key whose session it holds now goes to
//    the other replica;
//  - meanwhile the `vpm play` stream on it keeps getting frames;
//  - the replica then exits 0; the stream ends UNAVAILABLE, and `vpm play`
//    reopens its session on the survivor (volume reloaded from the data root,
//    events replayed) and finishes the script.
// Usage: node drain_test.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

import { runScenario } from '../web/harness.mjs';
import {
  exited, keyFor, kToken, makeDataRoot, replicaOf, replicaStates, sessionsByReplica, sleep,
  startBalancer, startReplicas, testPaths, track, vpm, vpmOk, waitUntil,
} from './cluster.mjs';

const { build, source, out } = testPaths(process.argv, 'drain');
const step = (text) => console.log(`balancer_drain: ${text}`);
const kDrainS = 5;   // docker/compose.yaml and docker/k8s/vpm-server.yaml
const kGraceS = 5;

const frameCount = (dir) => (fs.existsSync(dir) ? fs.readdirSync(dir).length : 0);

async function main() {
  const { dataRoot, source: volumeSource } = await makeDataRoot(build, out);
  const replicas = await startReplicas({
    build, out, n: 2, dataRoot, source: volumeSource,
    args: ['--drain-s', String(kDrainS), '--shutdown-grace-s', String(kGraceS)] });
  const balancer = await startBalancer({ source, out, replicas });
  const [victim, survivor] = replicas;
  const key = await keyFor({ build, balancer, replicas, replica: victim, source: volumeSource,
                             prefix: 'drain' });
  step(`key ${key} hashes to ${victim.name} (${victim.tag}); ${survivor.name} is ${survivor.tag}`);

  // A long `vpm play` on the victim: an orbit of 400 steps, 40 ms apart.
  const script = path.join(out, 'orbit.json');
  fs.writeFileSync(script, JSON.stringify({
    volume: volumeSource, settings: { width: 64, height: 64 }, interval_ms: 40,
    steps: [{ orbit: { to_azimuth_deg: 720, steps: 400 } }] }));
  const frames = path.join(out, 'frames');
  const report = path.join(out, 'play.json');
  const play = track(spawn(path.join(build, 'client', 'vpm'), [
    '--server', balancer.address, '--session-key', key, 'play', script, '--out-dir', frames,
    '--report', report], { env: { ...process.env, VPM_TOKEN: kToken },
                           stdio: ['ignore', 'pipe', 'pipe'] }));
  let playErr = '';
  play.stderr.on('data', (d) => { playErr += d; });
  play.stdout.on('data', () => {});
  const playDone = exited(play);
  await waitUntil(() => frameCount(frames) >= 10, 'frames of vpm play', 30000);
  const sessions = await sessionsByReplica(build, replicas);
  assert.equal(sessions[victim.name].length, 1, `the victim holds ${sessions[victim.name]}`);
  assert.equal(sessions[survivor.name].length, 0, `the survivor holds ${sessions[survivor.name]}`);

  const t0 = Date.now();
  const victimDone = exited(victim.child);
  victim.child.kill('SIGTERM');
  await waitUntil(async () => (await replicaStates(balancer))[victim.name]?.startsWith('DOWN'),
                  `HAProxy to mark ${victim.name} DOWN`, kDrainS * 1000, 50);
  const outAfterMs = Date.now() - t0;
  assert.equal(victim.child.exitCode, null, 'the replica stopped before the balancer saw it go');
  step(`SIGTERM: HAProxy took ${victim.name} out of rotation after ${outAfterMs} ms, ` +
       'while it still runs');

  // Still running and saying NOT_SERVING; the key now goes to the survivor;
  // the stream on the victim still gets frames.
  const framesAtOut = frameCount(frames);
  const health = await vpm(build, ['health', '--server', victim.address]);
  assert.equal(health.code, 1, `vpm health on the draining replica: ${health.stdout}${health.stderr}`);
  assert.match(health.stdout + health.stderr, /NOT_SERVING/);
  const moved = await vpmOk(build, ['--server', balancer.address, '--session-key', key,
                                    'volume', 'load', volumeSource]);
  assert.equal(replicaOf(replicas, moved.volume_id), survivor,
               `key ${key} still reaches ${replicaOf(replicas, moved.volume_id).name}`);
  await sleep(500);
  const framesLater = frameCount(frames);
  assert.equal(victim.child.exitCode, null, 'the drain ended too early to check the stream');
  assert.ok(framesLater > framesAtOut,
            `no frame on the draining replica's stream (${framesAtOut} -> ${framesLater})`);
  step(`draining: health NOT_SERVING, ${key} now reaches ${survivor.name}, ` +
       `the stream went on (${framesLater - framesAtOut} frames in 0.5 s)`);

  const { code, signal } = await victimDone;
  const stoppedAfterS = (Date.now() - t0) / 1000;
  assert.equal(code, 0, `the replica exited with ${code ?? signal}`);
  assert.ok(stoppedAfterS >= kDrainS - 0.5 && stoppedAfterS < kDrainS + kGraceS + 5,
            `the replica stopped ${stoppedAfterS} s after SIGTERM`);
  step(`${victim.name} exited 0 after ${stoppedAfterS.toFixed(1)} s`);

  const played = await playDone;
  assert.equal(played.code, 0, `vpm play exited ${played.code ?? played.signal}: ${playErr}`);
  assert.match(playErr, /lost \(UNAVAILABLE: the server is shutting down\)/, playErr);
  const r = JSON.parse(fs.readFileSync(report, 'utf8'));
  assert.equal(r.reopened, 1, JSON.stringify(r));
  assert.equal(replicaOf(replicas, r.sessions[0]), victim);
  assert.equal(replicaOf(replicas, r.sessions[1]), survivor);
  step(`vpm play: ${playErr.trim().split('\n').join(' / ')}; ${r.frames} frames in all`);
}

runScenario('balancer_drain', main);

// A replica killed (SIGKILL: no drain) behind HAProxy (docker/haproxy.cfg),
// three vpm-server replicas on loopback sharing one data root:
//  - `vpm play` on the victim: its stream ends with a clear status
//    (UNAVAILABLE, "the replica ... went away"), it reopens a session where
//    the balancer now sends its key (the volume reloaded from the data root,
//    the script's events so far replayed) and finishes the script;
//  - vpm-view (under Xvfb) on the victim: says the connection was lost,
//    opens a session on a survivor by itself and shows frames again;
//  - `vpm play` on another replica: its stream never stalls (no gap over
//    2.5 s in the 4 s after the kill, frames all along) and it is never
//    reopened;
//  - HAProxy marks the victim DOWN.
// Usage: node failover_test.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import { spawn, spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

import { runScenario } from '../web/harness.mjs';
import {
  exited, framesSince, keyFor, kToken, makeDataRoot, replicaOf, replicaStates, sleep,
  startBalancer, startReplicas, testPaths, track, waitUntil,
} from './cluster.mjs';

const { build, source, out } = testPaths(process.argv, 'failover');
const step = (text) => console.log(`balancer_failover: ${text}`);
const kMaxGapMs = 2500;

const frameCount = (dir) => (fs.existsSync(dir) ? fs.readdirSync(dir).length : 0);

// A child with its stdout and stderr collected in .out and .err.
function collect(child) {
  const c = { child, out: '', err: '' };
  child.stdout.on('data', (d) => { c.out += d; });
  child.stderr.on('data', (d) => { c.err += d; });
  return c;
}

// Xvfb on a free display; resolves with the display name.
async function startXvfb() {
  let display = null;
  for (let n = 90; n < 200 && !display; ++n) {
    if (!fs.existsSync(`/tmp/.X${n}-lock`) && !fs.existsSync(`/tmp/.X11-unix/X${n}`)) display = `:${n}`;
  }
  if (!display) throw new Error('no free X display in :90..:199');
  track(spawn('Xvfb', [display, '-screen', '0', '640x480x24', '-nolisten', 'tcp'],
              { stdio: 'ignore' }));
  await waitUntil(() => spawnSync('xdpyinfo', ['-display', display], { stdio: 'ignore' }).status === 0,
                  `Xvfb on ${display}`, 10000);
  return display;
}

function startPlay(balancer, key, script, name) {
  const dir = path.join(out, name);
  const report = path.join(out, `${name}.json`);
  const p = collect(track(spawn(path.join(build, 'client', 'vpm'), [
    '--server', balancer.address, '--session-key', key, 'play', script, '--out-dir', dir,
    '--report', report], { env: { ...process.env, VPM_TOKEN: kToken },
                           stdio: ['ignore', 'pipe', 'pipe'] })));
  return Object.assign(p, { dir, report, done: exited(p.child) });
}

async function main() {
  const { dataRoot, source: volumeSource } = await makeDataRoot(build, out);
  const replicas = await startReplicas({ build, out, n: 3, dataRoot, source: volumeSource });
  const balancer = await startBalancer({ source, out, replicas });
  const [victim, control] = replicas;
  const keyFor_ = (replica, prefix) => keyFor({ build, balancer, replicas, replica,
                                                source: volumeSource, prefix });
  const keyPlay = await keyFor_(victim, 'play');
  const keyView = await keyFor_(victim, 'view');
  const keyControl = await keyFor_(control, 'control');
  step(`victim ${victim.name}: keys ${keyPlay} (vpm play), ${keyView} (vpm-view); ` +
       `control ${control.name}: ${keyControl}`);

  // vpm-view on the victim.
  const display = await startXvfb();
  const view = collect(track(spawn(path.join(build, 'client', 'vpm-view'), [
    '--server', balancer.address, '--session-key', keyView, '--volume', volumeSource,
    '--size', '96', '96', '--log-frames'], {
    env: { ...process.env, VPM_TOKEN: kToken, DISPLAY: display },
    stdio: ['ignore', 'pipe', 'pipe'] })));
  const viewFrames = () => (view.out.match(/^frame /gm) ?? []).length;
  await waitUntil(() => viewFrames() > 0, 'the first frame of vpm-view', 60000);
  const viewSession = /opened session (\S+)/.exec(view.err)?.[1];
  assert.equal(replicaOf(replicas, viewSession), victim, `vpm-view opened ${viewSession}`);

  // Two long orbits: one on the victim, one on the control replica.
  const script = path.join(out, 'orbit.json');
  fs.writeFileSync(script, JSON.stringify({
    volume: volumeSource, settings: { width: 64, height: 64 }, interval_ms: 40,
    steps: [{ orbit: { to_azimuth_deg: 720, steps: 300 } }] }));
  const lost = startPlay(balancer, keyPlay, script, 'play-victim');
  const steady = startPlay(balancer, keyControl, script, 'play-control');
  await waitUntil(() => frameCount(lost.dir) >= 10 && frameCount(steady.dir) >= 10,
                  'frames of both vpm play runs', 60000);

  // The kill, while the control stream is watched every 50 ms.
  const samples = [];
  const watchUntil = Date.now() + 5000;
  const watching = (async () => {
    while (Date.now() < watchUntil) {
      samples.push({ t: Date.now(), n: frameCount(steady.dir) });
      await sleep(50);
    }
  })();
  await sleep(1000);
  const viewFramesAtKill = viewFrames();
  const tKill = Date.now();
  victim.child.kill('SIGKILL');
  await exited(victim.child);
  await watching;
  const { after: controlAfter, longestGap } = framesSince(samples, tKill);
  step(`SIGKILL ${victim.name}: the control stream on ${control.name} got ${controlAfter} frames ` +
       `in the next 4 s, longest gap ${longestGap} ms`);
  assert.ok(controlAfter >= 5, `the control stream got ${controlAfter} frames after the kill`);
  assert.ok(longestGap < kMaxGapMs, `the control stream stalled for ${longestGap} ms`);
  assert.ok((await replicaStates(balancer))[victim.name].startsWith('DOWN'),
            'HAProxy did not mark the killed replica DOWN');

  // vpm-view: connection lost, a session on a survivor, frames again.
  await waitUntil(() => (view.err.match(/opened session/g) ?? []).length >= 2 &&
                        viewFrames() > viewFramesAtKill,
                  'vpm-view to reopen and show frames', 60000);
  assert.match(view.err, /connection lost: the stream ended without a status: the vpm-server replica behind the balancer went away/);
  const reopened = [...view.err.matchAll(/opened session (\S+)/g)].at(-1)[1];
  assert.notEqual(replicaOf(replicas, reopened), victim);
  step(`vpm-view: ${view.err.split('\n').filter((l) => /lost|opened/.test(l)).slice(-2).join(' / ')}; ` +
       `${viewFrames() - viewFramesAtKill} frames since`);
  view.child.kill('SIGTERM');

  // vpm play on the victim: reopened and finished.
  const lostExit = await lost.done;
  assert.equal(lostExit.code, 0, `vpm play (victim) exited ${lostExit.code}: ${lost.err}`);
  assert.match(lost.err, /lost \(UNAVAILABLE: the stream ended without a status: the vpm-server replica behind the balancer went away\)/);
  const r = JSON.parse(fs.readFileSync(lost.report, 'utf8'));
  assert.equal(r.reopened, 1);
  assert.equal(replicaOf(replicas, r.sessions[0]), victim);
  assert.notEqual(replicaOf(replicas, r.sessions[1]), victim);
  step(`vpm play (victim): ${lost.err.trim().split('\n').join(' / ')}`);

  const steadyExit = await steady.done;
  assert.equal(steadyExit.code, 0, `vpm play (control) exited ${steadyExit.code}: ${steady.err}`);
  const c = JSON.parse(fs.readFileSync(steady.report, 'utf8'));
  assert.equal(c.reopened, 0, 'the control session was reopened');
  step(`vpm play (control): ${c.frames} frames, never reopened`);
}

runScenario('balancer_failover', main);

// Cases shared by the replicas through PostgreSQL (vpm-server --state),
// behind HAProxy (docker/haproxy.cfg): a surgeon's session on one replica is
// a case; that replica is killed (SIGKILL) mid-plan; the client opens the
// same case where the balancer now sends its key (`vpm case open`), and the
// survivor replays it from the shared database:
//  - every manipulation the client saw acknowledged is in the case;
//  - the reopened case shows the same largest displacement (within 1e-3 mm)
//    as the victim did at its last still;
//  - the client's pause (kill to the first still on the survivor) is
//    measured and printed.
// PostgreSQL runs as scripts/pg-test-server.sh starts it (unprivileged, a
// Unix socket only) and is stopped at the end.
// Usage: node failover_cases_test.mjs --build BUILD --source SOURCE
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

import { runScenario } from '../web/harness.mjs';
import {
  exited, keyFor, makeDataRoot, replicaOf, startBalancer, startReplicas, testPaths, vpm, vpmOk,
  waitUntil,
} from './cluster.mjs';

const { build, source, out } = testPaths(process.argv, 'failover_cases');
const step = (text) => console.log(`balancer_failover_cases: ${text}`);
const pgScript = path.join(source, 'scripts', 'pg-test-server.sh');
// A short folder: a Unix socket path is at most 107 bytes.
const pgDir = fs.mkdtempSync('/tmp/vpm-pg-failover-');

function pg(action) {
  const r = spawnSync(pgScript, [action, pgDir], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`pg-test-server.sh ${action}: ${r.stderr}${r.stdout}`);
}

// A still through the balancer, then the case as the store has it.
async function stillAndCase(server, key, sessionId, caseId, name) {
  await vpmOk(build, ['--server', server, '--session-key', key, 'snapshot', '--session', sessionId,
                      '--size', '96', '96', '--out', path.join(out, `${name}.png`)]);
  return vpmOk(build, ['--server', server, '--session-key', key, 'case', 'show', caseId, '--json']);
}

async function main() {
  pg('start');
  process.on('exit', () => spawnSync(pgScript, ['stop', pgDir]));
  const conninfo = fs.readFileSync(path.join(pgDir, 'conninfo'), 'utf8').trim();
  const { dataRoot, source: volumeSource } = await makeDataRoot(build, out);
  // No refinement on grab: its remesh event comes when the finer mesh is
  // built, after the grab's acknowledgement, so the events counted below
  // would depend on timing (a case reopened on the refined mesh:
  // RefineOnGrabTest.ACaseReopensOnTheRefinedMeshWithTheSameDeformation).
  // This 48^3 phantom was refined on grab from 89212f9 on; before, the
  // refinement was refused there (fewer than 3 x 20 voxels per axis).
  const replicas = await startReplicas({ build, out, n: 2, dataRoot, source: volumeSource,
                                         args: ['--state', conninfo, '--no-refine-on-grab'] });
  const balancer = await startBalancer({ source, out, replicas });
  const [victim, survivor] = replicas;
  const key = await keyFor({ build, balancer, replicas, replica: victim, source: volumeSource,
                             prefix: 'case' });
  const at = ['--server', balancer.address, '--session-key', key];

  // The plan on the victim: a kept drag, a second grab dragged.
  const volume = await vpmOk(build, [...at, 'volume', 'load', volumeSource]);
  const session = await vpmOk(build, [...at, 'session', 'open', '--volume-id', volume.volume_id]);
  assert.equal(replicaOf(replicas, session.session_id), victim);
  assert.match(session.case_id, /^case-[0-9a-f]{32}$/);
  // The middle of the volume's world box (LPS mm), where the grab goes.
  const [lo, hi] = volume.box_lps_mm ?? [];
  assert.ok(lo && hi, `volume load gave no box: ${JSON.stringify(volume)}`);
  const c = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
  const events = [
    ['--grab', ...c.map(String)], ['--drag', '0', '0', '3'], ['--drag', '0', '0', '6'],
    ['--release', '--keep'], ['--grab', String(c[0] + 8), String(c[1]), String(c[2])],
    ['--drag', '4', '0', '0'],
  ];
  let acked = 0;
  for (const e of events) {
    await vpmOk(build, [...at, 'manipulate', '--session', session.session_id, ...e]);
    ++acked;
  }
  const before = await stillAndCase(balancer.address, key, session.session_id, session.case_id,
                                    'before');
  assert.equal(before.events, acked);
  step(`plan on ${victim.name}: case ${session.case_id}, ${acked} events, largest ` +
       `displacement ${before.max_displacement_mm.toFixed(6)} mm`);

  // The survivor sees the case before anything happens (one database).
  const listed = await vpmOk(build, ['--server', survivor.address, 'case', 'list', '--json']);
  assert.ok(listed.cases.some((x) => x.case_id === session.case_id),
            'the survivor does not list the case');

  // Kill the victim; the client reopens the case where its key now goes.
  const killedAt = Date.now();
  victim.child.kill('SIGKILL');
  await exited(victim.child);
  const reopened = await waitUntil(async () => {
    const r = await vpm(build, [...at, 'case', 'open', session.case_id, '--json']);
    return r.code === 0 ? JSON.parse(r.stdout) : null;
  }, 'the case to reopen on the survivor', 60000, 100);
  assert.equal(replicaOf(replicas, reopened.session_id), survivor);
  const after = await stillAndCase(balancer.address, key, reopened.session_id, session.case_id,
                                   'after');
  const pauseMs = Date.now() - killedAt;
  assert.equal(after.events, acked, 'an acknowledged event was lost');
  const diff = Math.abs(after.max_displacement_mm - before.max_displacement_mm);
  step(`reopened on ${survivor.name} as ${reopened.session_id}: ${after.events} events, largest ` +
       `displacement ${after.max_displacement_mm.toFixed(6)} mm (difference ${diff.toExponential(2)}); ` +
       `pause from the kill to the first still ${pauseMs} ms`);
  assert.ok(diff < 1e-3, `largest displacement moved by ${diff} mm`);

  // The plan goes on on the survivor and is kept there too.
  await vpmOk(build, [...at, 'manipulate', '--session', reopened.session_id, '--drag', '6', '0', '0']);
  const more = await vpmOk(build, [...at, 'case', 'show', session.case_id, '--json']);
  assert.equal(more.events, acked + 1);
}

runScenario('balancer_failover_cases', main);

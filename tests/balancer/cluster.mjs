// What the balancer tests share: vpm-server replicas on loopback behind
// HAProxy running docker/haproxy.cfg itself (only its server-template line,
// which finds replicas by DNS, becomes one `server` line per replica), the
// `vpm` command line as the client, and the balancer's view of each replica.
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

import {
  closedPort, startServer, stopChild, track,
} from '../web/harness.mjs';

export const kToken = 'balancer-test-token';

// argv: --build DIR --source DIR; the output folder is BUILD/tests/balancer/NAME.
export function testPaths(argv, name) {
  const arg = (flag) => {
    const i = argv.indexOf(flag);
    if (i < 0 || !argv[i + 1]) throw new Error(`missing ${flag} DIR`);
    return path.resolve(argv[i + 1]);
  };
  const build = arg('--build');
  const source = arg('--source');
  const out = path.join(build, 'tests', 'balancer', name);
  fs.rmSync(out, { recursive: true, force: true });
  fs.mkdirSync(out, { recursive: true });
  return { build, source, out };
}

export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// Polls fn() every `everyMs` until it returns a truthy value (returned);
// throws `what` after timeoutMs.
export async function waitUntil(fn, what, timeoutMs = 30000, everyMs = 100) {
  const end = Date.now() + timeoutMs;
  for (;;) {
    const value = await fn();
    if (value) return value;
    if (Date.now() > end) throw new Error(`timed out after ${timeoutMs} ms waiting for ${what}`);
    await sleep(everyMs);
  }
}

// Runs `vpm ARGS` (the CLI); resolves {code, stdout, stderr}.
export function vpm(build, args, { env = {} } = {}) {
  return new Promise((resolve) => {
    const child = spawn(path.join(build, 'client', 'vpm'), args, {
      env: { ...process.env, VPM_TOKEN: kToken, ...env }, stdio: ['ignore', 'pipe', 'pipe'] });
    let stdout = '';
    let stderr = '';
    child.stdout.on('data', (d) => { stdout += d; });
    child.stderr.on('data', (d) => { stderr += d; });
    child.on('exit', (code, signal) => resolve({ code: code ?? signal, stdout, stderr }));
  });
}

// `vpm ARGS` that must succeed; resolves its stdout parsed as JSON when it
// is JSON, else as text.
export async function vpmOk(build, args, options) {
  const r = await vpm(build, args, options);
  if (r.code !== 0) {
    throw new Error(`vpm ${args.join(' ')} exited ${r.code}: ${r.stderr}${r.stdout}`);
  }
  try {
    return JSON.parse(r.stdout);
  } catch {
    return r.stdout;
  }
}

// The server tag in an id: "mesh-1a2b3c4d-<32 hex>" (volumes, meshes and
// sessions alike) -> "1a2b3c4d".
export function tagOf(id) {
  const m = /^[a-z]+-([0-9a-f]{8})-[0-9a-f]+$/.exec(id ?? '');
  if (!m) throw new Error(`'${id}' is not an id of a tagged vpm-server`);
  return m[1];
}

// A data root shared read-only by every replica, as in docker/compose.yaml,
// holding the phantom exported as NIfTI: the volume clients reload on a
// surviving replica. Returns {dataRoot, source} (source: the path under it).
export async function makeDataRoot(build, out) {
  const dataRoot = path.join(out, 'data');
  fs.mkdirSync(dataRoot, { recursive: true });
  await vpmOk(build, ['volume', 'export', 'phantom:abdomen?size=48',
                      path.join(dataRoot, 'abdomen48.nii.gz')]);
  return { dataRoot, source: 'abdomen48.nii.gz' };
}

// n replicas of vpm-server, each with metrics, the shared data root and
// `args`. Each replica's id tag is learned by loading `source` on it
// directly. Resolves [{name, child, address, port, metricsPort, tag}];
// name is the balancer's name for it (vpm-1, vpm-2, ...).
export async function startReplicas({ build, out, n, dataRoot, source, args = [] }) {
  const replicas = [];
  for (let i = 1; i <= n; ++i) {
    const r = await startServer({
      build, out, token: kToken, logName: `replica-${i}.log`,
      args: ['--metrics-listen', '127.0.0.1:0', '--data-root', dataRoot, ...args] });
    const volume = await vpmOk(build, ['--server', r.address, 'volume', 'load', source]);
    replicas.push({ ...r, name: `vpm-${i}`, tag: tagOf(volume.volume_id) });
  }
  return replicas;
}

// docker/haproxy.cfg with its one server-template line replaced by a
// `server` line per replica (same slot names, vpm-1.., so the same ids and
// ring), everything else as shipped.
export function balancerConfig(source, replicas) {
  const text = fs.readFileSync(path.join(source, 'docker', 'haproxy.cfg'), 'utf8');
  const lines = text.split('\n');
  const at = lines.flatMap((l, i) => (/^\s*server-template\s/.test(l) ? [i] : []));
  if (at.length !== 1) {
    throw new Error(`docker/haproxy.cfg: expected one server-template line, found ${at.length}`);
  }
  const m = /^(\s*)server-template\s+(\S+)\s/.exec(lines[at[0]]);
  const [indent, prefix] = [m[1], m[2]];
  if (prefix !== 'vpm-') throw new Error(`docker/haproxy.cfg: server-template prefix ${prefix}`);
  lines.splice(at[0], 1, ...replicas.map((r) => `${indent}server ${r.name} ${r.address}`));
  return lines.join('\n');
}

// HAProxy with balancerConfig() on free loopback ports; resolves once every
// replica is UP. {child, address, statsPort}.
export async function startBalancer({ source, out, replicas }) {
  const config = path.join(out, 'haproxy.cfg');
  fs.writeFileSync(config, balancerConfig(source, replicas));
  const [port, statsPort] = [await closedPort(), await closedPort()];
  const child = track(spawn('haproxy', ['-db', '-f', config], {
    env: { ...process.env, VPM_BALANCER_LISTEN: `127.0.0.1:${port}`,
           VPM_BALANCER_STATS: `127.0.0.1:${statsPort}` },
    stdio: ['ignore', 'pipe', 'pipe'] }));
  const log = fs.createWriteStream(path.join(out, 'haproxy.log'));
  child.stdout.pipe(log);
  child.stderr.pipe(log);
  const failed = new Promise((resolve, reject) => {
    child.on('error', (e) => reject(new Error(`haproxy: ${e.message} (scripts/install-deps.sh)`)));
    child.on('exit', (code) => reject(new Error(`haproxy exited (${code}); see ${out}/haproxy.log`)));
  });
  failed.catch(() => {});
  const balancer = { child, address: `127.0.0.1:${port}`, statsPort };
  // Servers start UP before their first check: wait for a passed check.
  await Promise.race([failed, waitUntil(async () => {
    const checks = await replicaChecks(balancer).catch(() => null);
    return checks && replicas.every((r) => checks[r.name] === 'L7OK');
  }, 'HAProxy\'s health check to pass on every replica', 20000, 200)]);
  return balancer;
}

// {replica name: a column of the stats page's CSV for it}.
async function statsColumn(balancer, column) {
  const response = await fetch(`http://127.0.0.1:${balancer.statsPort}/;csv`);
  const rows = (await response.text()).split('\n').filter((l) => l);
  const index = rows[0].replace(/^# /, '').split(',').indexOf(column);
  const values = {};
  for (const row of rows.slice(1)) {
    const f = row.split(',');
    if (f[0] === 'vpm_servers' && f[1] !== 'BACKEND') values[f[1]] = f[index];
  }
  return values;
}

// {replica name: HAProxy's status: UP, DOWN, MAINT, "UP 1/2", ...}.
export const replicaStates = (balancer) => statsColumn(balancer, 'status');
// {replica name: the last health check's result: L7OK, L7RSP, L4CON, ...}.
export const replicaChecks = (balancer) => statsColumn(balancer, 'check_status');

// The replica whose tag an id carries.
export function replicaOf(replicas, id) {
  const tag = tagOf(id);
  const r = replicas.find((x) => x.tag === tag);
  if (!r) throw new Error(`id ${id}: no replica has tag ${tag}`);
  return r;
}

// A session key the balancer sends to `replica`: tries key-PREFIX-0, -1, ...
// (LoadVolume of `source` through the balancer answers with the id of the
// replica it reached).
export async function keyFor({ build, balancer, replicas, replica, source, prefix }) {
  for (let i = 0; i < 64; ++i) {
    const key = `key-${prefix}-${i}`;
    const volume = await vpmOk(build, ['--server', balancer.address, '--session-key', key,
                                       'volume', 'load', source]);
    if (replicaOf(replicas, volume.volume_id) === replica) return key;
  }
  throw new Error(`no key of 64 hashes to ${replica.name}`);
}

// Sessions each replica holds, asked of each directly: {name: [session ids]}.
export async function sessionsByReplica(build, replicas) {
  const result = {};
  for (const r of replicas) {
    if (r.child.exitCode !== null || r.child.signalCode !== null) continue;
    const list = await vpmOk(build, ['--server', r.address, 'session', 'list']);
    result[r.name] = (Array.isArray(list) ? list : []).map((s) => s.session_id);
  }
  return result;
}

// A counter of a replica's Prometheus metrics, e.g.
// metric(r, 'vpm_requests_total', {method: 'Manipulate', code: 'OK'}); 0 when absent.
export async function metric(replica, name, labels = {}) {
  const text = await (await fetch(`http://127.0.0.1:${replica.metricsPort}/metrics`)).text();
  for (const line of text.split('\n')) {
    if (!line.startsWith(`${name}{`) && !line.startsWith(`${name} `)) continue;
    const ok = Object.entries(labels).every(([k, v]) => line.includes(`${k}="${v}"`));
    if (ok) return Number(line.trim().split(/\s+/).pop());
  }
  return 0;
}

// A stream watched across time t: `samples` [{t: ms, n: frames so far}] in
// time order. Returns {after: frames after t, longestGap: the longest time,
// ms, after t without a new frame (to the last sample)}.
export function framesSince(samples, t) {
  let lastChange = t;
  let longestGap = 0;
  for (let i = 1; i < samples.length; ++i) {
    if (samples[i].t < t || samples[i].n === samples[i - 1].n) continue;
    longestGap = Math.max(longestGap, samples[i].t - lastChange);
    lastChange = samples[i].t;
  }
  longestGap = Math.max(longestGap, samples.at(-1).t - lastChange);
  return { after: samples.at(-1).n - samples.find((s) => s.t >= t).n, longestGap };
}

// Resolves with the child's exit {code, signal}.
export function exited(child) {
  if (child.exitCode !== null || child.signalCode !== null) {
    return Promise.resolve({ code: child.exitCode, signal: child.signalCode });
  }
  return new Promise((resolve) => child.on('exit', (code, signal) => resolve({ code, signal })));
}

export { stopChild, track };

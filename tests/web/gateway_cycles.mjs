// Nothing a browser does by ordinary use exhausts the server: N (1,000)
// open/close cycles of a tab through the gateway on a real vpm-server with
// its default caps. Each cycle is what a browser tab does: sign-in cookie,
// WebSocket, open the phantom (the gateway reuses the loaded volume, builds
// or reuses the mesh, opens a session and an Interact stream), the first
// frame, then the tab goes away (the gateway closes the session and deletes
// the mesh). Checks: zero refusals (every cycle gets its frame, no error
// message); the server's RSS at the end within 10% of the RSS after the
// first 50 cycles; and the server's open streams, sessions, meshes, upload
// temporary files, threads and file descriptors (its Prometheus metrics)
// back to their values after the first cycle (the warm-up: the phantom
// loaded, pools and connections made), threads compared by name: gRPC
// core's executor may have grown to its fixed cap (2 per CPU), every other
// pool must be as it was. Figures go to
// BUILD/tests/web/gateway_cycles.json.
// Usage: node gateway_cycles.mjs --build BUILD --source SOURCE [--cycles N]
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { connect, request, signIn, startGatewayProcess } from './gateway_client.mjs';
import { randomToken, runScenario, startServer, testPaths } from './harness.mjs';

const argv = process.argv;
const { build, source, out } = testPaths(argv);
const cycles = Number(argv[argv.indexOf('--cycles') + 1]) || 1000;
const kSource = 'phantom:abdomen?size=48';
const kSettled = ['vpm_open_streams', 'vpm_sessions', 'vpm_meshes', 'vpm_upload_temp_files',
                  'vpm_process_threads', 'vpm_process_open_fds'];
const step = (text) => console.log(`gateway_cycles: ${text}`);
const kExecutor = 'default-executo';  // gRPC core's executor threads (names cut at 15)

async function metrics(port) {
  const r = await request(`http://127.0.0.1:${port}`, '/metrics');
  const values = { errors: 0, errorsByCall: {} };
  for (const line of r.body.split('\n')) {
    const m = /^(vpm_[a-z_]+) ([-\d.e+]+)$/.exec(line);
    if (m) values[m[1]] = Number(m[2]);
    // Refusals: a non-OK answer to a call that opens a tab, or a cap
    // (RESOURCE_EXHAUSTED) anywhere. The rest is the clean-up racing the
    // server's own (a cancelled stream ending as CANCELLED or "session
    // closed", DeleteMesh of a mesh still pinned or already gone): counted
    // apart, in the figures.
    const e = /^vpm_request_errors_total\{code="([A-Z_]+)",method="(\w+)",.*\} ([-\d.e+]+)$/.exec(line);
    if (e) {
      const opening = ['ListVolumes', 'GetVolume', 'LoadVolume', 'BuildMesh', 'OpenSession'];
      const refused = opening.includes(e[2]) || e[1] === 'RESOURCE_EXHAUSTED';
      values[refused ? 'errors' : 'cleanup'] = (values[refused ? 'errors' : 'cleanup'] ?? 0) + Number(e[3]);
      values.errorsByCall[`${e[2]} ${e[1]}`] = Number(e[3]);
    }
  }
  return values;
}

// Polls the metrics until `pred` holds (the server closes a tab's session,
// stream and mesh a little after the tab goes); returns the last values.
async function settle(port, pred, timeoutMs = 60000) {
  const deadline = Date.now() + timeoutMs;
  for (;;) {
    const m = await metrics(port);
    if (pred(m) || Date.now() > deadline) return m;
    await new Promise((r) => setTimeout(r, 100));
  }
}

// The server's threads by name (/proc/PID/task/*/comm), for the figures and
// for a failure message.
function threadNames(pid) {
  const names = {};
  for (const task of fs.readdirSync(`/proc/${pid}/task`)) {
    try {
      const name = fs.readFileSync(`/proc/${pid}/task/${task}/comm`, 'utf8').trim();
      names[name] = (names[name] ?? 0) + 1;
    } catch { /* ended meanwhile */ }
  }
  return names;
}

async function cycle(base, cookie) {
  const tab = await connect(source, base, { cookie });
  try {
    tab.send({ type: 'open', source: kSource, settings: { width: 64, height: 64 } });
    const first = await tab.next((m) => m.type === 'frame' || m.type === 'error', 60000);
    if (first.type === 'error') throw new Error(`refused: ${first.code} ${first.message}`);
    const errors = tab.inbox.filter((m) => m.type === 'error');
    if (errors.length) throw new Error(`refused: ${JSON.stringify(errors[0])}`);
  } finally {
    tab.ws.close();
    await tab.closed;
  }
}

async function main() {
  const token = randomToken();
  const server = await startServer({ build, out, token, logName: 'cycles_server.log',
                                     args: ['--metrics-listen', '127.0.0.1:0'] });
  let log = '';
  for (let i = 0; i < 50 && !/metrics on port \d+/.test(log); ++i) {
    await new Promise((r) => setTimeout(r, 100));  // the log is written as it comes
    log = fs.readFileSync(path.join(out, 'cycles_server.log'), 'utf8');
  }
  const metricsPort = Number(/metrics on port (\d+)/.exec(log)?.[1]);
  assert.ok(metricsPort > 0, `no metrics port in the server's log: ${log}`);
  const gatewayLog = fs.openSync(path.join(out, 'cycles_gateway.log'), 'w');
  const { child: gateway, base } = await startGatewayProcess({
    source, args: ['--server', server.address], env: { VPM_TOKEN: token }, stderr: gatewayLog });
  try {
    const cookie = await signIn(base, token);
    const idle = (m) => m.vpm_sessions === 0 && m.vpm_open_streams === 0 && m.vpm_meshes === 0;
    const t0 = performance.now();
    await cycle(base, cookie);  // warm-up
    const start = await settle(metricsPort, idle);
    const threadsAtStart = threadNames(server.child.pid);
    step(`after the first cycle: ${JSON.stringify(Object.fromEntries(
      [...kSettled, 'vpm_volumes', 'vpm_process_resident_bytes'].map((k) => [k, start[k]])))}`);
    let rssAt50 = null;
    for (let i = 2; i <= cycles; ++i) {
      await cycle(base, cookie);
      if (i === 50) {
        rssAt50 = (await settle(metricsPort, idle)).vpm_process_resident_bytes;
        step(`RSS after 50 cycles: ${(rssAt50 / 2 ** 20).toFixed(1)} MiB`);
      }
      if (i % 100 === 0) step(`${i} cycles, ${((performance.now() - t0) / i).toFixed(0)} ms each`);
    }
    const seconds = (performance.now() - t0) / 1000;
    // gRPC's core executor ("default-executor" threads) adds a thread when
    // its queue backs up, up to 2 per CPU, and keeps it: that pool is
    // bounded, not leaking. Every other thread, by name, must be back.
    const executorCap = Math.max(threadsAtStart[kExecutor] ?? 0, 2 * os.cpus().length);
    const extraExecutors = () => (threadNames(server.child.pid)[kExecutor] ?? 0) -
      (threadsAtStart[kExecutor] ?? 0);
    const backToStart = (m) => idle(m) && kSettled.every((k) =>
      m[k] === start[k] + (k === 'vpm_process_threads' ? extraExecutors() : 0));
    const end = await settle(metricsPort, backToStart);
    const rssEnd = end.vpm_process_resident_bytes;
    const figures = {
      cycles, seconds: Number(seconds.toFixed(1)), ms_per_cycle: Number((1000 * seconds / cycles).toFixed(1)),
      rss_after_50_mib: Number((rssAt50 / 2 ** 20).toFixed(1)),
      rss_end_mib: Number((rssEnd / 2 ** 20).toFixed(1)),
      server_refusals: end.errors,
      server_cleanup_codes: end.errorsByCall,
      start: Object.fromEntries(kSettled.map((k) => [k, start[k]])),
      end: Object.fromEntries(kSettled.map((k) => [k, end[k]])),
      threads_at_start: threadsAtStart,
      threads_at_end: threadNames(server.child.pid),
    };
    fs.writeFileSync(path.join(out, 'gateway_cycles.json'), JSON.stringify(figures, null, 2));
    step(`${cycles} cycles in ${figures.seconds} s (${figures.ms_per_cycle} ms each), zero refusals; ` +
         `RSS ${figures.rss_after_50_mib} -> ${figures.rss_end_mib} MiB`);
    step(`end: ${JSON.stringify(figures.end)}`);
    assert.equal(end.errors, 0, `the server refused calls: ${JSON.stringify(end.errorsByCall)}`);
    const threadsAtEnd = threadNames(server.child.pid);
    for (const [name, n] of Object.entries({ ...threadsAtStart, ...threadsAtEnd })) {
      if (name === kExecutor) {
        assert.ok(threadsAtEnd[name] <= executorCap, `${threadsAtEnd[name]} gRPC executor threads`);
      } else {
        assert.equal(threadsAtEnd[name] ?? 0, threadsAtStart[name] ?? 0,
                     `threads named ${name}: ${n} at the end, ${threadsAtStart[name] ?? 0} at the start`);
      }
    }
    for (const k of kSettled.filter((x) => x !== 'vpm_process_threads')) {
      assert.equal(end[k], start[k], `${k} did not come back to its start value`);
    }
    assert.equal(end.vpm_process_threads, start.vpm_process_threads + extraExecutors(),
                 'vpm_process_threads disagrees with the threads by name');
    assert.ok(Math.abs(rssEnd - rssAt50) <= 0.1 * rssAt50,
              `RSS ${rssEnd} bytes is not within 10% of ${rssAt50} after 50 cycles`);
    assert.equal(gateway.exitCode, null, 'the gateway exited');
  } finally {
    gateway.kill('SIGTERM');
  }
}

runScenario('gateway_cycles', main);

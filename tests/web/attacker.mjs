// The attacker's test of issue 25 (security), through the gateway: a real
// vpm-server with two users (alice, bob) and the gateway in front, and
// each attack a case (attacks/*.mjs, listed in attacks/cases.mjs) that
// asserts the fix. The server and the gateway start once; a case that
// kills the gateway starts it again (ctx.restartGateway).
//
// Usage: node attacker.mjs --build BUILD --source SOURCE [--case NAME ...]
//          [--gateway FILE]
// Without --case: every case whose fix is in this tree (attacks/cases.mjs;
// the ones waiting for a server fix are named there and run only when
// asked). --gateway runs another gateway.js (an older one, to show what a
// case finds before its fix). Figures: BUILD/tests/web/attacker.json;
// logs: attacker_server.log, attacker_gateway*.log.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';

import { kCases } from './attacks/cases.mjs';
import { connect, request, signIn, startGatewayProcess } from './gateway_client.mjs';
import { randomToken, runScenario, startServer, stopChild, testPaths, track,
         writeUsersFile } from './harness.mjs';
import { VpmClient } from '../../client/web/lib/vpm_client.js';

const argv = process.argv;
const { build, source, out } = testPaths(argv);
const asked = argv.flatMap((a, i) => (a === '--case' ? [argv[i + 1]] : []));
const gatewayScript = argv.includes('--gateway')
  ? path.resolve(argv[argv.indexOf('--gateway') + 1]) : null;
const step = (text) => console.log(`attacker: ${text}`);

// The server's Prometheus text as {name or name{labels}: value}.
async function metrics(port) {
  const r = await request(`http://127.0.0.1:${port}`, '/metrics');
  const values = {};
  for (const line of r.body.split('\n')) {
    const m = /^(vpm_[a-z_]+(?:\{[^}]*\})?) ([-\d.e+]+)$/.exec(line);
    if (m) values[m[1]] = Number(m[2]);
  }
  return values;
}

async function startCtx() {
  const tokens = { alice: randomToken(), bob: randomToken() };
  const usersFile = writeUsersFile(path.join(out, 'attacker_users.txt'), tokens);
  // A data root with a large volume whose load takes the server a second or
  // more (sign_out_work signs out while it is read).
  const dataRoot = path.join(out, 'attacker_data');
  fs.mkdirSync(dataRoot, { recursive: true });
  if (!fs.existsSync(path.join(dataRoot, 'big.nii.gz'))) {
    const made = spawnSync(path.join(build, 'client', 'vpm'),
                           ['volume', 'export', 'phantom:abdomen?size=256',
                            path.join(dataRoot, 'big.nii.gz')], { encoding: 'utf8' });
    assert.equal(made.status, 0, `vpm volume export: ${made.stderr}`);
  }
  const server = await startServer({
    build, out, token: randomToken(), logName: 'attacker_server.log',
    args: ['--users', usersFile, '--metrics-listen', '127.0.0.1:0',
           '--max-sessions-per-user', '3', '--data-root', dataRoot] });
  assert.ok(server.metricsPort > 0, 'the server printed no metrics port');
  const keyFile = path.join(out, 'attacker_cookie.key');
  fs.writeFileSync(keyFile, randomToken(), { mode: 0o600 });
  const sessionsFile = path.join(out, 'attacker_sessions.json');
  fs.rmSync(sessionsFile, { force: true });
  let starts = 0;
  const ctx = {
    build, source, out, tokens, server, step,
    grpc: new VpmClient({ address: server.address }),
    metrics: () => metrics(server.metricsPort),
    gateway: null,
    async startGateway() {
      const log = fs.openSync(path.join(out, `attacker_gateway${starts ? `_${starts}` : ''}.log`), 'w');
      starts += 1;
      // An older gateway (--gateway) may not know --sessions-file.
      const args = ['--server', server.address, '--users', usersFile, '--cookie-key-file', keyFile,
                    '--max-tabs-per-user', '16',
                    ...(gatewayScript ? [] : ['--sessions-file', sessionsFile])];
      const started = await startGatewayProcess({ source, args, stderr: log, script: gatewayScript });
      track(started.child);
      ctx.gateway = started;
      return started;
    },
    async killGateway() {
      ctx.gateway.child.kill('SIGKILL');
      await new Promise((r) => (ctx.gateway.child.exitCode !== null || ctx.gateway.child.signalCode
        ? r() : ctx.gateway.child.on('exit', r)));
    },
    async restartGateway() {
      if (ctx.gateway) await stopChild(ctx.gateway.child);
      return ctx.startGateway();
    },
    signIn: (user) => signIn(ctx.gateway.base, tokens[user]),
    tab: (cookie) => connect(source, ctx.gateway.base, { cookie }),
  };
  await ctx.startGateway();
  return ctx;
}

async function main() {
  const known = new Map(kCases.map((c) => [c.name, c]));
  for (const name of asked) assert.ok(known.has(name), `no case '${name}' (${[...known.keys()]})`);
  const cases = asked.length ? asked.map((n) => known.get(n)) : kCases.filter((c) => !c.waitsFor);
  const waiting = kCases.filter((c) => c.waitsFor && !asked.includes(c.name));
  for (const c of waiting) step(`not run (needs ${c.waitsFor}): ${c.name}`);
  const ctx = await startCtx();
  const figures = {};
  const failures = [];
  for (const c of cases) {
    step(`case ${c.name} (issue 25, ${c.point}) ...`);
    const t0 = performance.now();
    try {
      figures[c.name] = { ...(await c.run(ctx)), seconds: Number(((performance.now() - t0) / 1000).toFixed(1)) };
      step(`case ${c.name}: PASS ${JSON.stringify(figures[c.name])}`);
    } catch (e) {
      failures.push(c.name);
      // No token in the output, whatever a case's error quotes.
      let text = String(e?.stack ?? e);
      for (const [user, token] of Object.entries(ctx.tokens)) text = text.replaceAll(token, `${user}'s token`);
      figures[c.name] = { failed: text.split('\n')[0] };
      step(`case ${c.name}: FAIL: ${text}`);
    }
    if (ctx.gateway.child.exitCode !== null || ctx.gateway.child.signalCode !== null) {
      await ctx.startGateway();
    }
  }
  fs.writeFileSync(path.join(out, 'attacker.json'), JSON.stringify(figures, null, 2));
  ctx.grpc.close();
  assert.deepEqual(failures, [], `cases failed: ${failures.join(', ')}`);
}

runScenario('attacker', main);

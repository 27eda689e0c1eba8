// A client of the gateway as a browser tab is one, for the Node tests:
// signing in (POST /login, the cookie kept), and a WebSocket with that
// cookie and the page's Origin that queues what arrives (JSON messages, and
// frames unpacked as the page unpacks them).
import { spawn } from 'node:child_process';
import http from 'node:http';
import https from 'node:https';
import { createRequire } from 'node:module';
import path from 'node:path';

export function wsModule(source) {
  return createRequire(path.join(source, 'client', 'web', 'package.json'))('ws');
}

// The gateway as a child process; resolves with {child, base} once it
// prints its address (base: http(s)://127.0.0.1:PORT). script: another
// gateway.js to run (default: SOURCE's).
export function startGatewayProcess({ source, args = [], env = {}, stderr = 'inherit',
                                      script = null }) {
  const child = spawn(process.execPath, [script ?? path.join(source, 'client', 'web', 'gateway.js'),
                                         '--listen', '127.0.0.1:0', ...args],
                      { env: { ...process.env, VPM_TOKEN: '', ...env },
                        stdio: ['ignore', 'pipe', stderr] });
  return new Promise((resolve, reject) => {
    let seen = '';
    child.stdout.on('data', (chunk) => {
      seen += chunk;
      const m = /vpm-web listening on (https?:\/\/\S+?)\/ /.exec(seen);
      if (m) resolve({ child, base: m[1] });
    });
    child.on('exit', (code) => reject(new Error(`gateway exited ${code}: ${seen}`)));
  });
}

// One HTTP request; resolves with {status, headers, body}. options: method,
// headers, body (string), ca (PEM, for https). The target goes on the
// request line as given (`//host/` stays a path, as an attacker sends it).
export function request(base, target, { method = 'GET', headers = {}, body, ca } = {}) {
  const url = new URL(base);
  const lib = url.protocol === 'https:' ? https : http;
  return new Promise((resolve, reject) => {
    const req = lib.request({ protocol: url.protocol, hostname: url.hostname, port: url.port,
                              path: target, method, headers, ca }, (res) => {
      const chunks = [];
      res.on('data', (c) => chunks.push(c));
      res.on('end', () => resolve({ status: res.statusCode, headers: res.headers,
                                    body: Buffer.concat(chunks).toString() }));
    });
    req.on('error', reject);
    req.end(body);
  });
}

// Signs in with `token` through the form; resolves with the Cookie header
// value ("vpm_session=...") or rejects with the status.
export async function signIn(base, token, { ca } = {}) {
  const r = await request(base, '/login', {
    method: 'POST', ca, body: new URLSearchParams({ token }).toString(),
    headers: { 'Content-Type': 'application/x-www-form-urlencoded' } });
  const cookie = r.headers['set-cookie']?.[0];
  if (r.status !== 303 || !cookie) throw new Error(`sign-in: ${r.status} ${r.body}`);
  return cookie.split(';')[0];
}

// A tab's WebSocket: cookie (or none), Origin (default: base), extra
// headers. Resolves once open with {ws, next(pred, timeoutMs), send(obj),
// closed: Promise of {code, reason}}; rejects when the upgrade is refused.
export async function connect(source, base, { cookie, origin = base, headers = {}, ca } = {}) {
  const WebSocket = wsModule(source);
  const all = { ...headers };
  if (cookie) all.Cookie = cookie;
  if (origin) all.Origin = origin;
  const ws = new WebSocket(`${base.replace(/^http/, 'ws')}/ws`, { headers: all, ca });
  const inbox = [];
  const waiters = [];
  ws.on('message', (data, isBinary) => {
    let item;
    if (isBinary) {
      const n = data.readUInt32LE(0);
      const header = JSON.parse(data.subarray(4, 4 + n).toString());
      let at = 4 + n + header.bytes;
      item = { type: 'frame', header, image: data.subarray(4 + n, at),
               slices: (header.slices ?? []).map((s) => data.subarray(at, (at += s.bytes))),
               rest: data.length - at };
    } else {
      item = JSON.parse(data.toString());
    }
    inbox.push(item);
    for (const w of waiters.splice(0)) w();
  });
  const closed = new Promise((resolve) => ws.on('close', (code, reason) =>
    resolve({ code, reason: reason.toString() })));
  await new Promise((resolve, reject) => {
    ws.on('open', resolve);
    ws.on('error', reject);
  });
  // Resolves with the first queued item matching pred (removing it).
  const next = async (pred, timeoutMs = 5000) => {
    const deadline = Date.now() + timeoutMs;
    for (;;) {
      const i = inbox.findIndex(pred);
      if (i >= 0) return inbox.splice(i, 1)[0];
      if (Date.now() > deadline) {
        throw new Error(`nothing matching ${pred} in ${JSON.stringify(inbox).slice(0, 500)}`);
      }
      await new Promise((r) => {
        waiters.push(r);
        setTimeout(r, 100);
      });
    }
  };
  const send = (m) => ws.send(JSON.stringify(m));
  return { ws, next, send, closed, inbox };
}

#!/usr/bin/env node
// vpm-web: the web viewer's gateway, fit to face the internet. Serves the
// page (public/) over HTTP or HTTPS to signed-in browsers and bridges each
// tab's WebSocket (/ws) to vpm-server (lib/viewer_connection.js), calling
// the server as the signed-in user (that user's token as the bearer).
//
//   node gateway.js [--listen HOST:PORT] [--server HOST:PORT] [--proto FILE]
//                   [--users FILE] [--viewer-token TOKEN | --viewer-token-file FILE]
//                   [--allowed-host NAME ...] [--allowed-origin ORIGIN ...]
//                   [--tls-cert PEM --tls-key PEM]
//                   [--server-tls-ca PEM [--server-tls-cert PEM --server-tls-key PEM]]
//                   [--session-hours H] [--cookie-key-file FILE] [--max-tabs-per-user N]
//                   [--sessions-file FILE] [--max-upload-bytes N] [--max-uploads N]
//
// Who may sign in (lib/users.js): the users of --users (vpm-server's users
// file: each signs in with their own token) and the viewer token
// (--viewer-token-file, --viewer-token, $VPM_VIEWER_TOKEN, else $VPM_TOKEN:
// the user `viewer`). Sign-in and the sealed cookie (--cookie-key-file):
// lib/sign_ins.js; the HTTP
// routes: lib/http_handler.js. The WebSocket upgrade needs a signed-in
// cookie, an Origin from --allowed-origin (default: this gateway's own
// origin under each allowed host) and an allowed Host (--allowed-host;
// localhost, 127.0.0.1 and ::1 always): a page on another site, or one whose
// name an attacker points at this machine (DNS rebinding), is refused.
//
// --listen defaults to $VPM_WEB_LISTEN or 127.0.0.1:8080 (port 0 picks a
// free one); --server to $VPM_SERVER or 127.0.0.1:50051. Prints
// "vpm-web listening on http(s)://HOST:PORT/" once ready. GET /healthz
// answers 200 while the gateway runs (whether or not vpm-server is up). No
// input ends the process: a request or message that fails closes that one
// connection with a message. Each user's calls go on a channel of their own
// (lib/user_channels.js); --sessions-file keeps the ids of the sessions
// this process opened, so a gateway killed without closing them closes
// them when it runs again (lib/session_record.js). POST /upload takes a
// volume file from a signed-in tab to vpm-server's UploadVolume
// (lib/volume_upload.js): at most --max-upload-bytes, one per user, at most
// --max-uploads at once.
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import https from 'node:https';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';

import { WebSocketServer } from 'ws';

import { hostName, makeRequestHandler } from './lib/http_handler.js';
import { MeshRefs } from './lib/mesh_refs.js';
import { ProtoShape } from './lib/proto_shape.js';
import { SessionRecord } from './lib/session_record.js';
import { SignIns } from './lib/sign_ins.js';
import { staticHandler } from './lib/static_files.js';
import { Users } from './lib/users.js';
import { ViewerConnection } from './lib/viewer_connection.js';
import { kDefaultProtoPath, VpmClient } from './lib/vpm_client.js';
import { kDefaultMaxUploadBytes, kDefaultMaxUploads, VolumeUploads } from './lib/volume_upload.js';

const here = path.dirname(fileURLToPath(import.meta.url));
const kMaxControlMessageBytes = 64 * 1024;  // browser -> gateway JSON

const kUsage = `usage: node gateway.js [--listen HOST:PORT] [--server HOST:PORT] [--proto vpm.proto]
  [--users FILE] [--viewer-token TOKEN | --viewer-token-file FILE]
  [--allowed-host NAME ...] [--allowed-origin ORIGIN ...]
  [--tls-cert PEM --tls-key PEM] [--server-tls-ca PEM [--server-tls-cert PEM --server-tls-key PEM]]
  [--session-hours 12] [--cookie-key-file FILE] [--max-tabs-per-user 8] [--sessions-file FILE]
  [--max-upload-bytes 1073741824] [--max-uploads 4]
 --users: vpm-server's users file (NAME TOKEN-SHA256 lines); each user signs in with their token,
   which the gateway forwards to vpm-server as theirs
 --viewer-token(-file): one more token that signs in as the user 'viewer' (default:
   VPM_VIEWER_TOKEN, else VPM_TOKEN); forwarded to vpm-server likewise
 --allowed-host: a name browsers use to reach the gateway (localhost, 127.0.0.1 and ::1 always
   are; also VPM_WEB_ALLOWED_HOSTS=a,b); --allowed-origin: an origin (scheme://host:port) whose
   pages may open the WebSocket (default: this gateway under each allowed host)
 --tls-cert/--tls-key: serve HTTPS and WSS; --server-tls-ca: vpm-server uses TLS (its CA),
   --server-tls-cert/--server-tls-key: and wants a client certificate (mutual TLS)
 --cookie-key-file: a secret (16 bytes or more; or VPM_WEB_COOKIE_KEY) that seals the sign-in
   cookies; give every gateway replica the same one, and sign-ins survive restarts (default:
   random per process)
 --sessions-file: where this gateway records the sessions it opened (ids and user names, no
   token); one started after a kill closes the ones left open as their users come back (one
   file per gateway process; also VPM_WEB_SESSIONS_FILE)
 --max-upload-bytes: the largest volume file a browser may upload (vpm-server's own
   --max-upload-bytes applies too); --max-uploads: uploads at once in this gateway (each user
   one), each spooled to a temporary file under TMPDIR while it arrives
 VPM_WEB_LISTEN and VPM_SERVER set the defaults of --listen and --server
`;

function splitHostPort(value, flag) {
  const m = /^(.*):(\d+)$/.exec(value);
  if (!m || Number(m[2]) > 65535) throw new Error(`${flag}: '${value}' is not HOST:PORT`);
  return { host: m[1].replace(/^\[(.*)\]$/, '$1'), port: Number(m[2]) };
}

function readFile(file, flag) {
  try {
    return fs.readFileSync(file);
  } catch (e) {
    throw new Error(`${flag} ${file}: ${e.code === 'ENOENT' ? 'no such file' : e.message}`);
  }
}

function positive(value, flag) {
  const n = Number(value);
  if (!Number.isFinite(n) || n <= 0) throw new Error(`${flag}: '${value}' is not a positive number`);
  return n;
}

function parseOptions(argv) {
  const { values } = parseArgs({
    args: argv,
    options: {
      listen: { type: 'string', default: process.env.VPM_WEB_LISTEN || '127.0.0.1:8080' },
      server: { type: 'string', default: process.env.VPM_SERVER || '127.0.0.1:50051' },
      proto: { type: 'string', default: kDefaultProtoPath },
      users: { type: 'string' },
      'viewer-token': { type: 'string' },
      'viewer-token-file': { type: 'string' },
      'allowed-host': { type: 'string', multiple: true, default: [] },
      'allowed-origin': { type: 'string', multiple: true, default: [] },
      'tls-cert': { type: 'string' },
      'tls-key': { type: 'string' },
      'server-tls-ca': { type: 'string' },
      'server-tls-cert': { type: 'string' },
      'server-tls-key': { type: 'string' },
      'session-hours': { type: 'string', default: '12' },
      'cookie-key-file': { type: 'string' },
      'max-tabs-per-user': { type: 'string', default: '8' },
      'sessions-file': { type: 'string', default: process.env.VPM_WEB_SESSIONS_FILE || undefined },
      'max-upload-bytes': { type: 'string', default: String(kDefaultMaxUploadBytes) },
      'max-uploads': { type: 'string', default: String(kDefaultMaxUploads) },
      help: { type: 'boolean', default: false },
    },
  });
  if (values.help) {
    process.stdout.write(kUsage);
    process.exit(0);
  }
  splitHostPort(values.server, '--server');
  const allowedHosts = new Set(['localhost', '127.0.0.1', '::1']);
  const fromEnv = (process.env.VPM_WEB_ALLOWED_HOSTS ?? '').split(',');
  for (const name of [...values['allowed-host'], ...fromEnv]) {
    if (name.trim()) allowedHosts.add(name.trim().toLowerCase().replace(/^\[(.*)\]$/, '$1'));
  }
  const allowedOrigins = new Set();
  for (const origin of values['allowed-origin']) {
    let parsed;
    try {
      parsed = new URL(origin);
    } catch {
      throw new Error(`--allowed-origin: '${origin}' is not scheme://host[:port]`);
    }
    if (parsed.origin === 'null' || parsed.origin !== origin.replace(/\/$/, '').toLowerCase()) {
      throw new Error(`--allowed-origin: '${origin}' is not scheme://host[:port] (no path)`);
    }
    allowedOrigins.add(parsed.origin);
  }
  if (Boolean(values['tls-cert']) !== Boolean(values['tls-key'])) {
    throw new Error('TLS needs both --tls-cert and --tls-key');
  }
  const tls = values['tls-cert']
    ? { cert: readFile(values['tls-cert'], '--tls-cert'), key: readFile(values['tls-key'], '--tls-key') }
    : null;
  if (Boolean(values['server-tls-cert']) !== Boolean(values['server-tls-key'])) {
    throw new Error('mutual TLS needs both --server-tls-cert and --server-tls-key');
  }
  if (values['server-tls-cert'] && !values['server-tls-ca']) {
    throw new Error('--server-tls-cert needs --server-tls-ca');
  }
  const serverTls = values['server-tls-ca'] ? {
    ca: readFile(values['server-tls-ca'], '--server-tls-ca'),
    cert: values['server-tls-cert'] ? readFile(values['server-tls-cert'], '--server-tls-cert') : null,
    key: values['server-tls-key'] ? readFile(values['server-tls-key'], '--server-tls-key') : null,
  } : null;
  if (values['viewer-token'] && values['viewer-token-file']) {
    throw new Error('give one of --viewer-token and --viewer-token-file');
  }
  const viewerToken = values['viewer-token-file']
    ? readFile(values['viewer-token-file'], '--viewer-token-file').toString('utf8').trim()
    : (values['viewer-token'] ?? process.env.VPM_VIEWER_TOKEN ?? process.env.VPM_TOKEN ?? '');
  if (values['viewer-token-file'] && !viewerToken) {
    throw new Error(`--viewer-token-file ${values['viewer-token-file']}: empty`);
  }
  let cookieKey;
  const secret = values['cookie-key-file']
    ? readFile(values['cookie-key-file'], '--cookie-key-file')
    : (process.env.VPM_WEB_COOKIE_KEY ? Buffer.from(process.env.VPM_WEB_COOKIE_KEY) : null);
  if (secret) {
    if (secret.length < 16) throw new Error('the cookie key: at least 16 bytes of secret');
    cookieKey = crypto.createHash('sha256').update(secret).digest();
  }
  return {
    ...values, allowedHosts, allowedOrigins, tls, serverTls, cookieKey,
    users: Users.fromFile(values.users, viewerToken),
    sessionHours: positive(values['session-hours'], '--session-hours'),
    maxTabsPerUser: positive(values['max-tabs-per-user'], '--max-tabs-per-user'),
    maxUploadBytes: Math.floor(positive(values['max-upload-bytes'], '--max-upload-bytes')),
    maxUploads: Math.floor(positive(values['max-uploads'], '--max-uploads')),
    listen: splitHostPort(values.listen, '--listen'),
  };
}

function main() {
  let options;
  let client;
  try {
    options = parseOptions(process.argv.slice(2));
    client = new VpmClient({ address: options.server, protoPath: options.proto,
                             tls: options.serverTls });
  } catch (e) {
    process.stderr.write(`vpm-web: ${e.message}\n`);
    process.exit(2);
  }
  const log = (line) => process.stderr.write(`vpm-web: ${line}\n`);
  const shape = new ProtoShape(client.definition);
  const record = new SessionRecord(options['sessions-file'] ?? null, log);
  const signIns = new SignIns({ users: options.users, key: options.cookieKey,
                                maxAgeS: options.sessionHours * 3600, secure: Boolean(options.tls) });
  const scheme = options.tls ? 'https' : 'http';
  let port = 0;  // once listening
  const allowedHost = (req) => options.allowedHosts.has(hostName(req.headers.host));
  // This gateway under each allowed host, and every --allowed-origin.
  const allowedOrigin = (origin) => {
    if (typeof origin !== 'string' || origin.length > 300) return false;
    let parsed;
    try {
      parsed = new URL(origin);
    } catch {
      return false;
    }
    if (options.allowedOrigins.has(parsed.origin)) return true;
    const originPort = Number(parsed.port || (parsed.protocol === 'https:' ? 443 : 80));
    return parsed.protocol === `${scheme}:` && originPort === port &&
      options.allowedHosts.has(parsed.hostname.replace(/^\[(.*)\]$/, '$1'));
  };
  const tabs = new Map();  // tab id (hello.tab_id) -> its ViewerConnection
  const uploads = new VolumeUploads({ tabs, client, maxBytes: options.maxUploadBytes,
                                      maxUploads: options.maxUploads, allowedOrigin, log });
  const handler = makeRequestHandler({
    signIns, serveFile: staticHandler(path.join(here, 'public')), allowedHost, allowedOrigin,
    tls: Boolean(options.tls), log, upload: (...args) => uploads.handle(...args) });
  const server = options.tls ? https.createServer({ ...options.tls }, handler)
                             : http.createServer(handler);
  server.headersTimeout = 10000;
  // Off: it would end an upload that takes longer; the handler bounds the
  // other requests to 30 s itself (lib/http_handler.js).
  server.requestTimeout = 0;
  server.keepAliveTimeout = 5000;
  server.on('clientError', (err, socket) => {
    if (socket.writable && err.code !== 'ECONNRESET') {
      socket.end('HTTP/1.1 400 Bad Request\r\nConnection: close\r\n\r\n');
    } else {
      socket.destroy();
    }
  });
  if (options.tls) server.on('tlsClientError', () => {});

  const tabsOf = new Map();  // user -> open tabs
  const meshRefs = new MeshRefs();
  const wss = new WebSocketServer({ noServer: true, maxPayload: kMaxControlMessageBytes });
  const refuse = (socket, status, reason) => {
    socket.end(`HTTP/1.1 ${status} ${reason}\r\nConnection: close\r\n` +
               `Content-Type: text/plain\r\nContent-Length: ${reason.length + 1}\r\n\r\n${reason}\n`);
  };
  server.on('upgrade', (req, socket, head) => {
    socket.on('error', () => {});
    try {
      let pathname = null;
      try {
        pathname = new URL(req.url, 'http://gateway').pathname;
      } catch { /* refused below */ }
      if (pathname !== '/ws') return refuse(socket, 404, 'Not Found');
      if (!allowedHost(req)) return refuse(socket, 421, 'Misdirected Request');
      if (!allowedOrigin(req.headers.origin)) return refuse(socket, 403, 'Forbidden');
      const signIn = signIns.fromRequest(req);
      if (!signIn) return refuse(socket, 401, 'Unauthorized');
      if ((tabsOf.get(signIn.user) ?? 0) >= options.maxTabsPerUser) {
        return refuse(socket, 429, 'Too Many Requests');
      }
      return wss.handleUpgrade(req, socket, head, (ws) => {
        tabsOf.set(signIn.user, (tabsOf.get(signIn.user) ?? 0) + 1);
        signIns.addSocket(signIn.id, ws);
        ws.on('close', () => {
          const left = (tabsOf.get(signIn.user) ?? 1) - 1;
          if (left > 0) tabsOf.set(signIn.user, left);
          else tabsOf.delete(signIn.user);
        });
        try {
          const tab = new ViewerConnection({ ws, client, shape, meshRefs, token: signIn.token,
                                             user: signIn.user, record, log,
                                             maxUploadBytes: options.maxUploadBytes });
          tabs.set(tab.tabId, tab);
          ws.on('close', () => tabs.delete(tab.tabId));
        } catch (e) {
          log(`closing a connection after an unexpected error: ${e?.stack ?? e}`);
          ws.close(1011, 'internal error');
        }
      });
    } catch (e) {
      log(`upgrade failed: ${e?.stack ?? e}`);
      return socket.destroy();
    }
  });

  server.listen(options.listen.port, options.listen.host, () => {
    const { address } = server.address();
    port = server.address().port;
    const host = address.includes(':') ? `[${address}]` : address;
    process.stdout.write(`vpm-web listening on ${scheme}://${host}:${port}/ ` +
                         `(vpm-server ${options.server}${options.serverTls ? ', TLS' : ''})\n`);
  });
  server.on('error', (e) => {
    log(`cannot listen on ${options.listen.host}:${options.listen.port}: ${e.message}`);
    process.exit(1);
  });

  const stop = () => {
    for (const ws of wss.clients) ws.close(1001, 'gateway stopping');
    wss.close();
    server.close(() => {
      client.close();
      process.exit(0);
    });
    server.closeAllConnections?.();
    setTimeout(() => process.exit(0), 2000).unref();
  };
  process.on('SIGINT', stop);
  process.on('SIGTERM', stop);
}

main();

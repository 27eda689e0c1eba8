#!/usr/bin/env node
// vpm-web: the thin web viewer's gateway. Serves the page (public/) over
// HTTP and bridges each browser tab's WebSocket (/ws) to vpm-server's
// Interact stream (lib/viewer_connection.js). The server's token comes from
// VPM_TOKEN and stays here: the browser never sees it.
//
//   node gateway.js [--listen HOST:PORT] [--server HOST:PORT] [--proto FILE]
//                   [--allowed-host NAME ...]
//
// --listen defaults to $VPM_WEB_LISTEN or 127.0.0.1:8080 (port 0 picks a
// free one); --server to $VPM_SERVER or 127.0.0.1:50051. Prints
// "vpm-web listening on http://HOST:PORT/" once ready. GET /healthz answers
// 200 while the gateway runs (whether or not vpm-server is up).
//
// Every other request, the WebSocket upgrade included, must name an allowed
// host in its Host header (--allowed-host, repeatable, or the comma list in
// $VPM_WEB_ALLOWED_HOSTS; localhost, 127.0.0.1 and ::1 always): a page on
// another site whose name an attacker points at this machine (DNS
// rebinding) sends its own name as Host and is refused with 421.
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { parseArgs } from 'node:util';

import { WebSocketServer } from 'ws';

import { staticHandler } from './lib/static_files.js';
import { ViewerConnection } from './lib/viewer_connection.js';
import { kDefaultProtoPath, VpmClient } from './lib/vpm_client.js';

const here = path.dirname(fileURLToPath(import.meta.url));
const kMaxControlMessageBytes = 64 * 1024;  // browser -> gateway JSON

function splitHostPort(value, flag) {
  const m = /^(.*):(\d+)$/.exec(value);
  if (!m || Number(m[2]) > 65535) throw new Error(`${flag}: '${value}' is not HOST:PORT`);
  return { host: m[1].replace(/^\[(.*)\]$/, '$1'), port: Number(m[2]) };
}

function parseOptions(argv) {
  const { values } = parseArgs({
    args: argv,
    options: {
      listen: { type: 'string', default: process.env.VPM_WEB_LISTEN || '127.0.0.1:8080' },
      server: { type: 'string', default: process.env.VPM_SERVER || '127.0.0.1:50051' },
      proto: { type: 'string', default: kDefaultProtoPath },
      'allowed-host': { type: 'string', multiple: true, default: [] },
      help: { type: 'boolean', default: false },
    },
  });
  if (values.help) {
    process.stdout.write('usage: node gateway.js [--listen HOST:PORT] [--server HOST:PORT] ' +
                         '[--proto vpm.proto] [--allowed-host NAME ...]\n' +
                         '  the token for vpm-server comes from VPM_TOKEN; ' +
                         'VPM_WEB_LISTEN and VPM_SERVER set the defaults of --listen and --server;\n' +
                         '  --allowed-host: a name browsers use to reach the gateway (localhost, ' +
                         '127.0.0.1 and ::1 always are; also VPM_WEB_ALLOWED_HOSTS=a,b)\n');
    process.exit(0);
  }
  splitHostPort(values.server, '--server');
  const allowedHosts = new Set(['localhost', '127.0.0.1', '::1']);
  const fromEnv = (process.env.VPM_WEB_ALLOWED_HOSTS ?? '').split(',');
  for (const name of [...values['allowed-host'], ...fromEnv]) {
    if (name.trim()) allowedHosts.add(name.trim().toLowerCase().replace(/^\[(.*)\]$/, '$1'));
  }
  return { ...values, allowedHosts, listen: splitHostPort(values.listen, '--listen') };
}

// The host name of a Host header ("name:port", "[v6]:port"), lower case;
// null when it does not parse.
function hostName(header) {
  if (typeof header !== 'string' || header === '') return null;
  try {
    return new URL(`http://${header}/`).hostname.toLowerCase().replace(/^\[(.*)\]$/, '$1');
  } catch {
    return null;
  }
}

// Only pages served by this gateway may open its WebSocket: another site in
// the same browser must not drive the server with the gateway's token.
function sameOrigin(info) {
  const { origin } = info;
  if (!origin) return true;  // not a browser (e.g. a script)
  try {
    return new URL(origin).host === info.req.headers.host;
  } catch {
    return false;
  }
}

function main() {
  let options;
  try {
    options = parseOptions(process.argv.slice(2));
  } catch (e) {
    process.stderr.write(`vpm-web: ${e.message}\n`);
    process.exit(2);
  }
  const client = new VpmClient({
    address: options.server, token: process.env.VPM_TOKEN ?? '', protoPath: options.proto });
  const log = (line) => process.stderr.write(`vpm-web: ${line}\n`);
  const serveFile = staticHandler(path.join(here, 'public'));
  const allowedHost = (req) => options.allowedHosts.has(hostName(req.headers.host));
  const server = http.createServer((req, res) => {
    if (req.url === '/healthz') {
      res.writeHead(200, { 'Content-Type': 'text/plain' }).end('ok\n');
    } else if (!allowedHost(req)) {
      res.writeHead(421, { 'Content-Type': 'text/plain' })
        .end(`vpm-web: '${hostName(req.headers.host) ?? ''}' is not an allowed host ` +
             '(start the gateway with --allowed-host NAME)\n');
    } else {
      serveFile(req, res);
    }
  });
  const wss = new WebSocketServer({
    server, path: '/ws', maxPayload: kMaxControlMessageBytes,
    verifyClient: (info) => allowedHost(info.req) && sameOrigin(info) });
  wss.on('connection', (ws) => new ViewerConnection({ ws, client, log }));

  server.listen(options.listen.port, options.listen.host, () => {
    const { address, port } = server.address();
    const host = address.includes(':') ? `[${address}]` : address;
    process.stdout.write(`vpm-web listening on http://${host}:${port}/ ` +
                         `(vpm-server ${options.server})\n`);
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
    setTimeout(() => process.exit(0), 2000).unref();
  };
  process.on('SIGINT', stop);
  process.on('SIGTERM', stop);
}

main();

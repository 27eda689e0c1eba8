// POST /upload: a volume file from a signed-in browser's tab, passed to
// vpm-server's UploadVolume as that tab's user (docs/WEB.md, "Uploads").
//
//   POST /upload
//   Content-Type: application/octet-stream
//   Content-Length: N                (required; at most --max-upload-bytes)
//   Origin: the gateway's            (required, as for the WebSocket)
//   X-Vpm-Tab: TAB_ID                (the tab's `hello.tab_id`: its user, token and
//                                     x-vpm-session key, so that the volume lands on the
//                                     replica that serves the tab)
//   X-Vpm-File-Name: NAME            (percent-encoded UTF-8; public/upload_files.js's rule)
//   body: the file's bytes
// -> 200 {volume: VolumeInfo}, else {code, message} (code: a gRPC status name)
//    with 400, 401, 403, 405, 409, 411, 413, 415, 429, 503 or 507 before
//    anything is read, and a status after (httpStatusOf).
//
// The server's header carries the file's SHA-256 before its bytes, so the
// gateway spools the body to a temporary file under os.tmpdir() while it
// hashes it, then streams the file in 1 MiB chunks. The file is unlinked as
// soon as it is open: its bytes live while the gateway holds it open and go
// when it is closed, however the upload ends (a SIGKILL included), and no
// other process can open it. Spooling also keeps a slow browser off the
// server: the server reserves memory for an upload while it arrives, and
// ends one that averages under its --upload-min-bytes-per-s; from the spool
// the bytes go at disk speed.
//
// Bounds: one upload per user at a time (429), --max-uploads for the whole
// gateway (503), the byte cap by Content-Length before reading (413) and
// while reading, free space under the temporary folder (507), and 60 s
// without a byte from the browser ends the upload. The tab's closing (or its
// user's sign-out) cancels it, and so does the browser going away. Progress
// goes to the tab's WebSocket ({type: 'upload_progress', stage: 'sending' |
// 'reading', bytes, total_bytes}). Patient data: file names may carry a
// patient's name, so nothing here logs one, nor the server's text (which
// may quote it): sizes, users and status codes only.
import crypto from 'node:crypto';
import { once } from 'node:events';
import fsp from 'node:fs/promises';
import os from 'node:os';
import path from 'node:path';

import { uploadFileName } from '../public/upload_files.js';
import { explainError } from './explain_error.js';
import { GrpcStatus, statusName } from './vpm_client.js';

export const kDefaultMaxUploadBytes = 2 ** 30;  // vpm-server's default --max-upload-bytes
export const kDefaultMaxUploads = 4;
const kChunkBytes = 2 ** 20;           // the server takes 64 KiB to 1 MiB a chunk
const kIdleMs = 60000;                 // no byte from the browser for this long ends it
const kProgressEveryMs = 250;
const kDiskMarginBytes = 64 * 2 ** 20; // left free under the temporary folder
const kMaxNameHeaderChars = 3 * 255;   // 255 UTF-8 bytes, percent-encoded

const kHttpStatus = {
  OK: 200, INVALID_ARGUMENT: 422, FAILED_PRECONDITION: 409, RESOURCE_EXHAUSTED: 429,
  UNAUTHENTICATED: 401, PERMISSION_DENIED: 403, NOT_FOUND: 404, CANCELLED: 499,
  UNAVAILABLE: 503, DEADLINE_EXCEEDED: 504,
};
// The HTTP status of a gRPC status name, once the body was read.
export const httpStatusOf = (code) => kHttpStatus[code] ?? 502;

class Refusal extends Error {
  constructor(status, code, message) {
    super(message);
    Object.assign(this, { status, code });
  }
}

// The words for a failed UploadVolume; `name` is the file as the user
// named it (shown to that user only).
export function explainUploadError(err, name, address) {
  const details = String(err?.details ?? err?.message ?? err).slice(0, 500);
  switch (err?.code) {
    case GrpcStatus.INVALID_ARGUMENT:
      return `vpm-server cannot read ${name} as a volume: ${details}`;
    case GrpcStatus.RESOURCE_EXHAUSTED:
      return `${name} does not fit within vpm-server's limits now: ${details}`;
    case GrpcStatus.CANCELLED:
      return `The upload of ${name} was cancelled.`;
    case GrpcStatus.DEADLINE_EXCEEDED:
      return `vpm-server did not finish reading ${name} in time (${details}).`;
    default:
      return explainError(err, `Uploading ${name}`, address);
  }
}

async function writeAll(fh, chunk, position) {
  for (let done = 0; done < chunk.length;) {
    const { bytesWritten } = await fh.write(chunk, done, chunk.length - done, position + done);
    done += bytesWritten;
  }
}

async function readAll(fh, buffer, position) {
  for (let done = 0; done < buffer.length;) {
    const { bytesRead } = await fh.read(buffer, done, buffer.length - done, position + done);
    if (bytesRead === 0) throw new Error('the spooled file is shorter than written');
    done += bytesRead;
  }
}

// An open temporary file that no name reaches: made in a private folder
// (0700) under tmpDir, which is removed before this returns.
async function anonymousFile(tmpDir) {
  const dir = await fsp.mkdtemp(path.join(tmpDir, 'vpm-web-upload-'));
  try {
    return await fsp.open(path.join(dir, 'spool'), 'wx+', 0o600);
  } finally {
    await fsp.rm(dir, { recursive: true, force: true });
  }
}

export class VolumeUploads {
  // tabs: Map tab id -> ViewerConnection; client: the VpmClient; maxBytes:
  // the cap of one upload; maxUploads: uploads at once in this gateway;
  // allowedOrigin(origin); log(line); tmpDir: where files are spooled.
  constructor({ tabs, client, maxBytes = kDefaultMaxUploadBytes, maxUploads = kDefaultMaxUploads,
                allowedOrigin, log = () => {}, tmpDir = os.tmpdir() }) {
    Object.assign(this, { tabs, client, maxBytes, maxUploads, allowedOrigin, log, tmpDir });
    this.busyUsers = new Set();
  }

  // The request handler (http_handler.js): signIn is the cookie's sign-in
  // or null.
  async handle(req, res, signIn) {
    let admitted;
    try {
      admitted = await this.admit(req, signIn);
    } catch (e) {
      if (!(e instanceof Refusal)) throw e;
      const declared = Number(req.headers['content-length']) || 0;
      this.log(`upload refused: ${e.status} ${e.code}${signIn ? ` (${signIn.user})` : ''}, ` +
               `${declared} bytes declared`);
      // The body is not read: the connection closes after the answer.
      return answer(res, e.status, { code: e.code, message: e.message }, { Connection: 'close' });
    }
    const { tab, name, bytes } = admitted;
    let outcome;
    try {
      outcome = await this.run(req, res, tab, name, bytes);
    } finally {
      this.busyUsers.delete(tab.user);
    }
    // Once the spool is closed and the user free: the page may send the next.
    return answer(res, ...outcome);
  }

  // The tab, name and size of an upload that may start, its user then
  // counted busy (handle() lets go); throws a Refusal.
  async admit(req, signIn) {
    if (req.method !== 'POST') throw new Refusal(405, 'INVALID_ARGUMENT', 'Uploads are POSTed.');
    if (!signIn) throw new Refusal(401, 'UNAUTHENTICATED', 'Sign in first (/login).');
    if (!this.allowedOrigin(req.headers.origin)) {
      throw new Refusal(403, 'PERMISSION_DENIED', 'An upload from another site.');
    }
    const type = String(req.headers['content-type'] ?? '').split(';')[0].trim().toLowerCase();
    if (type !== 'application/octet-stream') {
      throw new Refusal(415, 'INVALID_ARGUMENT', 'Send the file as application/octet-stream.');
    }
    const tab = this.tabs.get(String(req.headers['x-vpm-tab'] ?? ''));
    if (!tab || tab.closed || tab.user !== signIn.user) {
      throw new Refusal(409, 'FAILED_PRECONDITION',
                        'This page is not connected to the gateway; try again once it is.');
    }
    const name = decodedName(req.headers['x-vpm-file-name']);
    if (req.headers['content-length'] === undefined) {
      throw new Refusal(411, 'INVALID_ARGUMENT', 'The upload needs a Content-Length.');
    }
    const bytes = Number(req.headers['content-length']);
    if (!Number.isSafeInteger(bytes) || bytes <= 0) {
      throw new Refusal(400, 'INVALID_ARGUMENT', `${name} is empty.`);
    }
    if (bytes > this.maxBytes) {
      throw new Refusal(413, 'RESOURCE_EXHAUSTED', `${name} is ${bytes} bytes; this gateway takes ` +
                        `uploads of at most ${this.maxBytes} bytes.`);
    }
    const { bavail, bsize } = await fsp.statfs(this.tmpDir);
    if (bavail * bsize < bytes + kDiskMarginBytes) {
      throw new Refusal(507, 'RESOURCE_EXHAUSTED', 'The gateway has no room on its disk for ' +
                        `${name} now (${bytes} bytes).`);
    }
    // No await from these checks to the add: two requests cannot both pass.
    if (this.busyUsers.has(signIn.user)) {
      throw new Refusal(429, 'RESOURCE_EXHAUSTED',
                        'You have an upload under way; wait for it to end, or cancel it.');
    }
    if (this.busyUsers.size >= this.maxUploads) {
      throw new Refusal(503, 'RESOURCE_EXHAUSTED',
                        'The gateway is taking as many uploads as it may; try again in a minute.');
    }
    this.busyUsers.add(signIn.user);
    return { tab, name, bytes };
  }

  // Spools, sends and returns the answer: [status, body, headers].
  async run(req, res, tab, name, bytes) {
    const started = Date.now();
    let fh = null;
    let code = 'OK';
    try {
      fh = await anonymousFile(this.tmpDir);
      const sha256 = await this.receive(req, fh, bytes, name, tab);
      const volume = await this.send(fh, { file_name: name, total_bytes: bytes, sha256_hex: sha256 },
                                     tab, res);
      return [200, { volume }];
    } catch (e) {
      code = typeof e.code === 'number' ? statusName(e.code) : (e.code ?? 'failed');
      return this.failure(e, name, tab);
    } finally {
      await fh?.close();
      this.log(`upload of ${bytes} bytes as ${tab.user}: ${code} in ${Date.now() - started} ms`);
    }
  }

  // The body into fh, hashed as it comes; resolves with its SHA-256 (hex).
  // Rejects when the browser goes, stalls for kIdleMs, sends other than
  // Content-Length, or the disk fails; the tab's closing cancels it.
  async receive(req, fh, bytes, name, tab) {
    const hash = crypto.createHash('sha256');
    const idle = setTimeout(() => req.destroy(new Refusal(
      408, 'DEADLINE_EXCEEDED', `Nothing of ${name} arrived for ${kIdleMs / 1000} s; the upload ` +
      'stopped.')), kIdleMs);
    const stop = { cancel: () => req.destroy(new Refusal(
      499, 'CANCELLED', `The upload of ${name} was cancelled: the page's connection closed.`)) };
    tab.track(stop);  // the tab may have closed while the spool was made
    let size = 0;
    try {
      for await (const chunk of req) {
        idle.refresh();
        if ((size += chunk.length) > bytes) {
          throw new Refusal(413, 'RESOURCE_EXHAUSTED', `${name}: more bytes than announced.`);
        }
        hash.update(chunk);
        await writeAll(fh, chunk, size - chunk.length);
      }
    } finally {
      clearTimeout(idle);
      tab.calls.delete(stop);
    }
    if (size !== bytes) throw new Error('truncated');
    return hash.digest('hex');
  }

  // UploadVolume from fh as the tab's user (its token and x-vpm-session
  // key): the header, then 1 MiB chunks (the last shorter), each written
  // once the stream takes it. Resolves with the VolumeInfo; rejects with
  // the gRPC error. Cancelled when the browser goes or the tab closes.
  async send(fh, header, tab, res) {
    let ended = false;
    let settle;
    const result = new Promise((resolve) => { settle = resolve; });
    const call = this.client.uploadVolume(tab.as, (err, volume) => {
      ended = true;
      tab.calls.delete(call);
      settle({ err, volume });
    });
    tab.track(call);
    res.on('close', () => {
      if (!res.writableFinished) call.cancel();
    });
    call.write({ header });
    const total = header.total_bytes;
    let shownAt = 0;
    for (let at = 0; at < total && !ended;) {
      const chunk = Buffer.allocUnsafe(Math.min(kChunkBytes, total - at));
      await readAll(fh, chunk, at);
      at += chunk.length;
      if (!call.write({ chunk })) await Promise.race([once(call, 'drain').catch(() => {}), result]);
      if (at === total || Date.now() - shownAt >= kProgressEveryMs) {
        shownAt = Date.now();
        tab.send({ type: 'upload_progress', stage: 'sending', bytes: at, total_bytes: total });
      }
    }
    if (!ended) {
      call.end();
      tab.send({ type: 'upload_progress', stage: 'reading', bytes: total, total_bytes: total });
    }
    const { err, volume } = await result;
    if (err) throw err;
    return volume;
  }

  // The answer to a failed upload, in words: [status, body, headers].
  failure(e, name, tab) {
    if (typeof e.code === 'number') {  // the server's answer
      if (e.code === GrpcStatus.UNAVAILABLE) tab.serverDown(e);
      return [httpStatusOf(statusName(e.code)),
              { code: statusName(e.code), message: explainUploadError(e, name, this.client.address) }];
    }
    const close = { Connection: 'close' };  // the body may not have been read whole
    if (e instanceof Refusal) return [e.status, { code: e.code, message: e.message }, close];
    if (['ENOSPC', 'EDQUOT', 'EFBIG'].includes(e.code)) {
      return [507, { code: 'RESOURCE_EXHAUSTED',
                     message: `The gateway ran out of disk while taking ${name}.` }, close];
    }
    if (e.syscall) {  // the temporary folder failed otherwise
      return [500, { code: 'INTERNAL', message: `The gateway could not keep ${name} on its disk ` +
                     `(${e.code}).` }, close];
    }
    // The browser went (ECONNRESET) before the end.
    return [400, { code: 'CANCELLED', message: `The upload of ${name} stopped before its end.` },
            close];
  }
}

// The X-Vpm-File-Name header as the name sent to the server; throws a Refusal.
function decodedName(header) {
  let name;
  try {
    if (typeof header !== 'string' || header.length > kMaxNameHeaderChars) throw new Error();
    name = decodeURIComponent(header);
  } catch {
    throw new Refusal(400, 'INVALID_ARGUMENT', 'X-Vpm-File-Name: a percent-encoded file name.');
  }
  try {
    return uploadFileName(name);
  } catch (e) {
    throw new Refusal(400, 'INVALID_ARGUMENT', `Not a file to upload: ${e.message}.`);
  }
}

// A JSON answer, unless the browser is gone.
function answer(res, status, body, headers = {}) {
  if (res.headersSent || res.destroyed) return;
  res.writeHead(status, { 'Content-Type': 'application/json', 'Cache-Control': 'no-store', ...headers })
    .end(JSON.stringify(body));
}

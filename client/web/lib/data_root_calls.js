// The "Server files" section's calls for one browser tab (docs/WEB.md,
// "Server files"), made as the tab's signed-in user: one folder of the
// server's --data-root. A listed volume opens with {type: 'open', source}
// as any source does.
//
//   {type: 'data_ls', path}  ListDataRoot -> {type: 'data_listing', path, entries, truncated}
//        entries: [{name, kind ('FOLDER' | 'VOLUME_FILE' | 'DICOM_FOLDER' | 'ARCHIVE' |
//        'OTHER_FILE' | 'NOT_OPENABLE'), size_bytes, modified_unix_ms, source}]
// A failure is {type: 'data_error', path, code, message, allowed}: allowed
// is false when the user may not browse (PERMISSION_DENIED from the
// server for the root), and the page then hides the section.
import { explainError } from './explain_error.js';
import { GrpcStatus, isServerDown, statusName } from './vpm_client.js';

export const kMaxDataPathBytes = 4096;  // the server's kMaxSourcePathBytes
const kControl = /[\u0000-\u001f\u007f]/;

// Returns the message, or null when its type is not a data root message.
// Throws for a path that is not a relative path without '..'.
export function parseDataRootMessage(message) {
  if (message.type !== 'data_ls') return null;
  const unknown = Object.keys(message).find((k) => !['type', 'path'].includes(k));
  if (unknown !== undefined) throw new Error(`data_ls: no field '${unknown.slice(0, 32)}'`);
  const { path } = message;
  if (typeof path !== 'string' || Buffer.byteLength(path, 'utf8') > kMaxDataPathBytes ||
      kControl.test(path) || path.startsWith('/') || path.split('/').includes('..')) {
    throw new Error(`path: a folder relative to the data root (at most ${kMaxDataPathBytes} ` +
                    "bytes, no '..', not absolute)");
  }
  return message;
}

export class DataRootCalls {
  // connection: the tab's ViewerConnection (rpc, send, log, client, serverDown).
  constructor(connection) {
    this.connection = connection;
    this.op = 0;
  }

  // A newer listing supersedes the one under way: only its answer comes back.
  async list({ path }) {
    const c = this.connection;
    const op = ++this.op;
    try {
      const r = await c.rpc('ListDataRoot', { path });
      if (op !== this.op) return;
      c.send({ type: 'data_listing', path: r.path, truncated: Boolean(r.truncated),
               entries: r.entries.map((e) => ({
                 name: e.name, kind: e.kind, size_bytes: Number(e.size_bytes),
                 modified_unix_ms: Number(e.modified_unix_ms), source: e.source })) });
    } catch (err) {
      if (op !== this.op || c.closed) return;
      c.log(`ListDataRoot: ${statusName(err?.code)}`);
      const denied = err?.code === GrpcStatus.PERMISSION_DENIED && path === '';
      const noRoot = err?.code === GrpcStatus.FAILED_PRECONDITION ||
                     err?.code === GrpcStatus.UNIMPLEMENTED;
      c.send({ type: 'data_error', path, code: statusName(err?.code),
               allowed: !(denied || noRoot),
               message: explainError(err, `Listing the server's folder '${path || '/'}'`,
                                     c.client.address) });
      if (isServerDown(err)) c.serverDown(err);
    }
  }
}

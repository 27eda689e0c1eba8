// The stand-in server's UploadVolume (fake_vpm_server.mjs), with the real
// server's rules (server/service/upload_volume_reactor.h): the header first
// (a plain file name with an extension the server reads, total_bytes
// positive and at most maxBytes, sha256_hex 64 hex digits), then chunks of
// 64 KiB to 1 MiB (only the last shorter), never more than declared; at the
// end the size and the SHA-256 must match. Then, as the server reads the
// file: content starting with 'bad' is INVALID_ARGUMENT (the server's
// "NAME: ..." naming the file), a name holding 'huge' RESOURCE_EXHAUSTED;
// otherwise, after readMs, a VolumeInfo of source upload:NAME owned by the
// token's user (volumeOf(name, owner) makes and remembers it).
// Each upload is kept in `list`: {header, chunks (sizes), bytes (Buffer),
// authorization, affinity, cancelled, answer: the status code name or 'OK'}.
import crypto from 'node:crypto';

const kMinChunk = 64 * 1024;
const kMaxChunk = 1024 * 1024;
const kExtensions = ['.nii', '.nii.gz', '.nrrd', '.mha', '.zip', '.tar', '.tar.gz', '.tgz'];

export function makeUploads(grpc, users, volumeOf) {
  const state = { list: [], readMs: 0, maxBytes: 2 ** 30 };
  const headerFault = (h) => {
    const name = h?.file_name ?? '';
    if (!name || /[/\\]/.test(name) || name === '.' || name === '..') {
      return 'header.file_name: give a plain file name (no folders)';
    }
    if (!kExtensions.some((ext) => name.endsWith(ext))) return `header.file_name: '${name}' must end in ...`;
    if (!(h.total_bytes > 0)) return 'header.total_bytes: must be positive';
    if (!/^[0-9a-fA-F]{64}$/.test(h.sha256_hex)) return 'header.sha256_hex: must be 64 hexadecimal digits';
    return null;
  };
  state.take = (call, callback) => {
    const auth = call.metadata.get('authorization')[0] ?? null;
    const upload = { header: null, chunks: [], parts: [], bytes: null, authorization: auth,
                     affinity: call.metadata.get('x-vpm-session')[0] ?? null, cancelled: false,
                     answer: null };
    state.list.push(upload);
    let received = 0;
    const finish = (code, details, volume = null) => {
      if (upload.answer) return;
      upload.answer = code;
      if (code === 'OK') callback(null, volume);
      else callback({ code: grpc.status[code], details });
    };
    call.on('data', (m) => {
      if (upload.answer) return;
      if (!upload.header) {
        const fault = m.part !== 'header' ? 'the first message must be the header' : headerFault(m.header);
        if (fault) return finish('INVALID_ARGUMENT', fault);
        if (m.header.total_bytes > state.maxBytes) {
          return finish('RESOURCE_EXHAUSTED', `header.total_bytes: ${m.header.total_bytes} is over the upload cap`);
        }
        upload.header = m.header;
        return undefined;
      }
      if (m.part !== 'chunk') return finish('INVALID_ARGUMENT', 'a second header');
      const size = m.chunk.length;
      received += size;
      if (received > upload.header.total_bytes) {
        return finish('INVALID_ARGUMENT', 'chunk: more bytes than header.total_bytes');
      }
      const last = received === upload.header.total_bytes;
      if (size > kMaxChunk || (size < kMinChunk && !last)) {
        return finish('INVALID_ARGUMENT', `chunk: ${size} bytes; chunks are 64 KiB to 1 MiB`);
      }
      upload.chunks.push(size);
      upload.parts.push(Buffer.from(m.chunk));
      return undefined;
    });
    call.on('end', () => {
      if (upload.answer) return;
      const { header } = upload;
      if (!header || received !== header.total_bytes) {
        finish('INVALID_ARGUMENT', `truncated: ${received} of ${header?.total_bytes ?? '?'} bytes`);
        return;
      }
      upload.bytes = Buffer.concat(upload.parts);
      upload.parts = [];
      const sha = crypto.createHash('sha256').update(upload.bytes).digest('hex');
      if (sha !== header.sha256_hex.toLowerCase()) {
        finish('INVALID_ARGUMENT', 'sha256 mismatch');
        return;
      }
      upload.readTimer = setTimeout(() => {
        if (upload.cancelled) return;
        if (upload.bytes.subarray(0, 3).toString() === 'bad') {
          finish('INVALID_ARGUMENT', `${header.file_name}: not a NIfTI-1 file (sizeof_hdr is 25185)`);
        } else if (header.file_name.includes('huge')) {
          finish('RESOURCE_EXHAUSTED', 'volume: 2048 x 2048 x 2048 int16 is 16 GiB, over ' +
                 '--max-volume-bytes (512 MiB)');
        } else {
          const owner = users[String(auth).replace(/^Bearer /, '')] ?? 'default';
          finish('OK', null, volumeOf(header.file_name, owner));
        }
      }, state.readMs);
    });
    call.on('cancelled', () => {
      clearTimeout(upload.readTimer);
      upload.cancelled = true;
      upload.answer ??= 'CANCELLED';
    });
  };
  return state;
}

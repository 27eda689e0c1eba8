// A ZIP archive of stored (uncompressed) entries, made in the browser from
// the files a user dropped: DICOM files are compressed already or compress
// poorly, and storing them costs one read for the CRC-32 and no CPU else.
// The archive is a Blob of parts (headers and the files themselves), so the
// files' bytes are read once for the checksum and once more when sent,
// never held in memory together.
//
// Format (APPNOTE.TXT 6.3): per entry a local file header, then the bytes;
// then the central directory and its end record. Method 0 (stored), the
// names UTF-8 (flag bit 11), every time stamp 1980-01-01 00:00 (the
// archive's bytes depend on the files alone). No ZIP64: at most 65,535
// entries and offsets under 4 GiB, far above what an upload may carry.
// Also loads in Node (tests): it needs only Blob, TextEncoder and DataView.

export const kMaxZipEntries = 0xffff;
const kMaxZipBytes = 0xffffffff;
const kLocalHeaderBytes = 30;
const kCentralHeaderBytes = 46;
const kEndRecordBytes = 22;
const kUtf8NamesFlag = 0x0800;
const kDosDate1980 = (1 << 5) | 1;  // 1980-01-01: day 1, month 1, year 0
const kReadSliceBytes = 4 << 20;    // bytes read at once for the CRC

const kCrcTable = (() => {
  const table = new Uint32Array(256);
  for (let n = 0; n < 256; ++n) {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    table[n] = c >>> 0;
  }
  return table;
})();

// CRC-32 (ISO-HDLC, the ZIP one) of `bytes` (a Uint8Array), continuing
// from `crc` (the CRC of what came before; 0 to start).
export function crc32(bytes, crc = 0) {
  let c = ~crc >>> 0;
  for (let i = 0; i < bytes.length; ++i) c = kCrcTable[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return ~c >>> 0;
}

const utf8 = (text) => new TextEncoder().encode(text);

// The archive's size in bytes for entries [{name, blob}], without reading
// them (to refuse one over a cap before any work).
export function storedZipBytes(entries) {
  let total = kEndRecordBytes;
  for (const { name, blob } of entries) {
    const nameBytes = utf8(name).length;
    total += kLocalHeaderBytes + kCentralHeaderBytes + 2 * nameBytes + blob.size;
  }
  return total;
}

function localHeader(nameBytes, crc, size) {
  const out = new Uint8Array(kLocalHeaderBytes + nameBytes.length);
  const v = new DataView(out.buffer);
  v.setUint32(0, 0x04034b50, true);  // signature
  v.setUint16(4, 10, true);          // version needed: 1.0, stored
  v.setUint16(6, kUtf8NamesFlag, true);
  v.setUint16(8, 0, true);           // method: stored
  v.setUint16(10, 0, true);          // time
  v.setUint16(12, kDosDate1980, true);
  v.setUint32(14, crc, true);
  v.setUint32(18, size, true);       // compressed size
  v.setUint32(22, size, true);       // uncompressed size
  v.setUint16(26, nameBytes.length, true);
  v.setUint16(28, 0, true);          // extra field length
  out.set(nameBytes, kLocalHeaderBytes);
  return out;
}

function centralHeader(nameBytes, crc, size, offset) {
  const out = new Uint8Array(kCentralHeaderBytes + nameBytes.length);
  const v = new DataView(out.buffer);
  v.setUint32(0, 0x02014b50, true);  // signature
  v.setUint16(4, (3 << 8) | 20, true);  // made by: Unix, 2.0
  v.setUint16(6, 10, true);
  v.setUint16(8, kUtf8NamesFlag, true);
  v.setUint16(10, 0, true);
  v.setUint16(12, 0, true);
  v.setUint16(14, kDosDate1980, true);
  v.setUint32(16, crc, true);
  v.setUint32(20, size, true);
  v.setUint32(24, size, true);
  v.setUint16(28, nameBytes.length, true);
  // 30: extra, 32: comment, 34: disk number, 36: internal attributes: 0
  v.setUint32(38, (0o100644 << 16) >>> 0, true);  // external: a regular file, rw-r--r--
  v.setUint32(42, offset, true);
  out.set(nameBytes, kCentralHeaderBytes);
  return out;
}

function endRecord(count, directoryBytes, directoryOffset) {
  const out = new Uint8Array(kEndRecordBytes);
  const v = new DataView(out.buffer);
  v.setUint32(0, 0x06054b50, true);
  v.setUint16(8, count, true);   // entries on this disk
  v.setUint16(10, count, true);  // entries in all
  v.setUint32(12, directoryBytes, true);
  v.setUint32(16, directoryOffset, true);
  return out;
}

// The CRC-32 of a Blob, read a slice at a time; onBytes(n) after each.
async function blobCrc(blob, onBytes, signal) {
  let crc = 0;
  for (let at = 0; at < blob.size; at += kReadSliceBytes) {
    signal?.throwIfAborted();
    const slice = new Uint8Array(await blob.slice(at, at + kReadSliceBytes).arrayBuffer());
    crc = crc32(slice, crc);
    onBytes(slice.length);
  }
  return crc;
}

// A Blob (type application/zip) holding entries [{name, blob}] stored, in
// order. Names must be distinct plain names (upload_files.js makes them).
// onProgress(readBytes, totalBytes) while the CRCs are computed; signal: an
// AbortSignal that stops it (the promise rejects with its reason).
export async function storeZip(entries, { onProgress = () => {}, signal = null } = {}) {
  if (entries.length > kMaxZipEntries) {
    throw new Error(`${entries.length} files; a ZIP without ZIP64 holds at most ${kMaxZipEntries}`);
  }
  if (storedZipBytes(entries) > kMaxZipBytes) throw new Error('the files come to 4 GiB or more');
  const totalBytes = entries.reduce((sum, e) => sum + e.blob.size, 0);
  let readBytes = 0;
  const parts = [];
  const central = [];
  let offset = 0;
  for (const { name, blob } of entries) {
    const nameBytes = utf8(name);
    const crc = await blobCrc(blob, (n) => onProgress((readBytes += n), totalBytes), signal);
    const header = localHeader(nameBytes, crc, blob.size);
    parts.push(header, blob);
    central.push(centralHeader(nameBytes, crc, blob.size, offset));
    offset += header.length + blob.size;
  }
  const directoryBytes = central.reduce((sum, c) => sum + c.length, 0);
  return new Blob([...parts, ...central, endRecord(entries.length, directoryBytes, offset)],
                  { type: 'application/zip' });
}

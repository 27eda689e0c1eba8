// The names of the PACS API as vpm-server checks them (docs/PACS.md), shared
// by the page (which endpoint a volume came from, for Export) and the
// gateway (lib/validate_pacs_message.js, before anything reaches the server).

// An endpoint of the server's --pacs file: 1-64 letters, digits, '.', '_',
// '-', not starting with '.'.
export const kPacsEndpointPattern = /^[A-Za-z0-9_-][A-Za-z0-9._-]{0,63}$/;
// A DICOM UID: digit components separated by dots, at most 64 characters.
const kUidPattern = /^[0-9]+(\.[0-9]+)*$/;
export const kMaxUidChars = 64;

export function isPacsEndpoint(name) {
  return typeof name === 'string' && kPacsEndpointPattern.test(name);
}

export function isDicomUid(uid) {
  return typeof uid === 'string' && uid.length <= kMaxUidChars && kUidPattern.test(uid);
}

// The most stacks a source may name (the server's kMaxDicomStack).
const kMaxStack = 100000;

// source: a LoadVolumeRequest.source. Returns {endpoint, studyUid, seriesUid,
// stack} for pacs:ENDPOINT/STUDY_UID/SERIES_UID[?stack=N] (stack 0 when the
// source names none), else null.
export function parsePacsSource(source) {
  if (typeof source !== 'string' || !source.startsWith('pacs:')) return null;
  const [path, query, ...more] = source.slice('pacs:'.length).split('?');
  if (more.length) return null;
  let stack = 0;
  if (query !== undefined) {
    const m = /^stack=([1-9][0-9]{0,5})$/.exec(query);
    if (!m || Number(m[1]) > kMaxStack) return null;
    stack = Number(m[1]);
  }
  const parts = path.split('/');
  if (parts.length !== 3) return null;
  const [endpoint, studyUid, seriesUid] = parts;
  if (!isPacsEndpoint(endpoint) || !isDicomUid(studyUid) || !isDicomUid(seriesUid)) return null;
  return { endpoint, studyUid, seriesUid, stack };
}

// The endpoint a volume's source names (the part between 'pacs:' and the
// first '/'), or null when the source is not a PACS series.
export function pacsEndpointOf(source) {
  return parsePacsSource(source)?.endpoint ?? null;
}

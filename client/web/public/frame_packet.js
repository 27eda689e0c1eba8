// Reads one frame message of the gateway (client/web/lib/frame_packet.js):
// a 32-bit little-endian header length, the JSON header, the image bytes,
// then each slice's image (header.slices[i].bytes each, in order).
const mime = (encoding) => (encoding === 'png' ? 'image/png' : 'image/jpeg');

export function unpackFrame(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  let at = 4 + length;
  const image = new Blob([new Uint8Array(buffer, at, header.bytes)], { type: mime(header.encoding) });
  at += header.bytes;
  const slices = (header.slices ?? []).map((s) => {
    const blob = new Blob([new Uint8Array(buffer, at, s.bytes)], { type: mime(s.encoding) });
    at += s.bytes;
    return { header: s, image: blob };
  });
  return { header, image, slices };
}

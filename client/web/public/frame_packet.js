// Reads one frame message of the gateway (client/web/lib/frame_packet.js):
// a 32-bit little-endian header length, the JSON header, the image bytes.
export function unpackFrame(buffer) {
  const length = new DataView(buffer).getUint32(0, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 4, length)));
  const type = header.encoding === 'png' ? 'image/png' : 'image/jpeg';
  const image = new Blob([new Uint8Array(buffer, 4 + length)], { type });
  return { header, image };
}

// One frame as one binary WebSocket message:
//   bytes 0..3   header length N, unsigned 32-bit little-endian
//   bytes 4..4+N the header, UTF-8 JSON (sizes, sequence, timings)
//   the rest     the encoded image (JPEG, or PNG when the settings ask for it)
// The browser reads it back in public/frame_packet.js.

import { encodingName } from './render_settings.js';

// frame: a vpm.v2.Frame as loaded by proto-loader (snake_case fields);
// extra: fields the gateway adds (e.g. gateway_dropped).
export function packFrame(frame, extra = {}) {
  const image = Buffer.from(frame.image ?? []);
  const header = {
    encoding: encodingName(frame.encoding),
    width: frame.width,            // pixels of this frame (half size while interactive)
    height: frame.height,
    last_sequence: Number(frame.last_sequence),
    interactive: frame.interactive,
    timings: frame.timings,        // server-side ms per stage
    max_displacement_mm: frame.max_displacement_mm,
    frame_number: Number(frame.frame_number),
    superseded_frames: Number(frame.superseded_frames),
    vertices: frame.vertices_mm?.length ?? 0,
    bytes: image.length,
    ...extra,
  };
  const json = Buffer.from(JSON.stringify(header), 'utf8');
  const prefix = Buffer.alloc(4);
  prefix.writeUInt32LE(json.length, 0);
  return Buffer.concat([prefix, json, image]);
}

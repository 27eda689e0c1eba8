// One frame as one binary WebSocket message:
//   bytes 0..3   header length N, unsigned 32-bit little-endian
//   bytes 4..4+N the header, UTF-8 JSON (sizes, sequence, timings, slices)
//   the rest     the encoded image (JPEG, or PNG when the settings ask for
//                it), then each slice's image in the order of
//                header.slices (header.bytes and slices[i].bytes long)
// The browser reads it back in public/frame_packet.js.

import { encodingName } from './render_settings.js';

// A SliceGeometry as the page uses it (world LPS points and vectors as
// [x, y, z], mm).
function sliceGeometry(g = {}) {
  const v = (p) => [p?.x ?? 0, p?.y ?? 0, p?.z ?? 0];
  return {
    orientation: g.orientation,
    origin_mm: v(g.origin_mm),          // world LPS: the corner of pixel (0, 0)
    step_u_mm: v(g.step_u_mm),          // one pixel right, world mm
    step_v_mm: v(g.step_v_mm),          // one pixel down, world mm
    world_normal: v(g.world_normal),
    pixel_mm: g.pixel_mm,
    offset_mm: g.offset_mm,             // the plane's position along its normal (world)
    min_offset_mm: g.min_offset_mm,     // where it still meets the volume
    max_offset_mm: g.max_offset_mm,
    window: g.window ?? null,
    cut_tets: Number(g.cut_tets ?? -1),
  };
}

// frame: a vpm.v3.Frame as loaded by proto-loader (snake_case fields);
// extra: fields the gateway adds (e.g. gateway_dropped).
export function packFrame(frame, extra = {}) {
  const image = Buffer.from(frame.image ?? []);
  const slices = (frame.slices ?? []).map((s) => ({ s, image: Buffer.from(s.image ?? []) }));
  const header = {
    encoding: encodingName(frame.encoding),
    width: frame.width,            // pixels of this frame (half size while interactive)
    height: frame.height,
    last_sequence: Number(frame.last_sequence),
    interactive: frame.interactive,
    // Refinement at rest: 1, 2, ... for the rungs before the still, else 0.
    refine_level: Number(frame.refine_level ?? 0),
    timings: frame.timings,        // server-side ms per stage
    max_displacement_mm: frame.max_displacement_mm,
    inverted_tets: Number(frame.inverted_tets ?? 0),  // of the proxy mesh (0 expected)
    lag_mm: frame.lag_mm ?? 0,     // how far the grabbed tissue is behind the pointer
    // The held grab's point (world LPS), as the server picked it.
    grab_point_mm: frame.grab_point_mm
      ? [frame.grab_point_mm.x, frame.grab_point_mm.y, frame.grab_point_mm.z] : null,
    // The mesh this frame ran on: a grab refines it by itself, and frames
    // then name the finer mesh.
    mesh_id: frame.mesh_id ?? '',
    frame_number: Number(frame.frame_number),
    superseded_frames: Number(frame.superseded_frames),
    vertices: frame.vertices_mm?.length ?? 0,
    bytes: image.length,
    slices: slices.map(({ s, image: bytes }) => ({
      view: s.view,
      encoding: encodingName(s.encoding),
      width: s.width,
      height: s.height,
      bytes: bytes.length,
      geometry: sliceGeometry(s.geometry),
    })),
    ...extra,
  };
  const json = Buffer.from(JSON.stringify(header), 'utf8');
  const prefix = Buffer.alloc(4);
  prefix.writeUInt32LE(json.length, 0);
  return Buffer.concat([prefix, json, image, ...slices.map((x) => x.image)]);
}

// A stand-in for vpm-server in Node (grpc-js on the project's vpm.proto)
// for the gateway's own tests: it answers the calls the gateway makes,
// records each call's method, request and metadata, and streams one small
// frame per Interact event. A grab with pixel_x < 0 fails the stream with
// OUT_OF_RANGE, as the real server does for a pick outside the volume.
// Frames carry one small slice per RenderSettings.slices entry of the
// stream's settings; ReadTransferFunction answers a two-point function named
// after the file, or INVALID_ARGUMENT for text 'bad'.
// Sessions belong to the bearer token that opened them: GetSession and Watch
// with another token are PERMISSION_DENIED unless the session was shared
// (share(sessionId, token)); a Watch sends a frame every 20 ms until
// revoke(sessionId, token) ends it with PERMISSION_DENIED, as the server
// does when a share is revoked (CloseSession ends it with
// FAILED_PRECONDITION "session ... is closed"). With tls = {cert, key} it serves TLS.
// Cases (docs/CASES.md) once keepCases(true), as with --state-dir: every
// OpenSession makes one, owned by the token's user (`users`: {token: name});
// grab, drag, release and pin events count as its events; Undo and redo
// move one event; the last settings of an Interact stream are its view
// (CaseInfo.view, without the per-client size, overlay and encoding), which
// GetCase returns; before that, the case calls answer FAILED_PRECONDITION
// with the server's message.
// The PACS calls (ListPacsEndpoints, SearchStudies, ListSeries, LoadVolume of
// pacs: sources with GetLoadProgress, ExportDicom) are fake_pacs.mjs's, with
// the endpoints of setPacs([...]) (none: a server without --pacs).
// UploadVolume checks what the real server checks (fake_upload.mjs) and
// keeps each upload in `uploads` (header, chunk sizes, bytes, metadata,
// whether it was cancelled); the volume it answers opens like any other.
import { createRequire } from 'node:module';
import path from 'node:path';

import { makePacs } from './fake_pacs.mjs';
import { makeUploads } from './fake_upload.mjs';

export async function startFakeServer(source, { tls = null, users = {} } = {}) {
  const require = createRequire(path.join(source, 'client', 'web', 'package.json'));
  const grpc = require('@grpc/grpc-js');
  const protoLoader = require('@grpc/proto-loader');
  const definition = protoLoader.loadSync(
    path.join(source, 'proto', 'vpm', 'v3', 'vpm.proto'),
    { keepCase: true, longs: Number, enums: String, defaults: true, oneofs: true,
      includeDirs: [path.join(source, 'proto')] });
  const { Vpm } = grpc.loadPackageDefinition(definition).vpm.v3;

  const calls = [];  // {method, request, metadata: {authorization, session}}
  const record = (method, call) => {
    const md = call.metadata;
    calls.push({ method, request: call.request ?? null,
                 authorization: md.get('authorization')[0] ?? null,
                 affinity: md.get('x-vpm-session')[0] ?? null });
  };
  const volume = { volume_id: 'vol-1', source: 'phantom:loaded', dims: [11, 11, 11],
                   spacing_mm: { x: 1, y: 1, z: 1 }, direction: [1, 0, 0, 0, 1, 0, 0, 0, 1] };
  let next = 1;
  const loaded = new Map();  // volume id -> VolumeInfo of LoadVolume
  const remember = (v) => {
    loaded.set(v.volume_id, v);
    return v;
  };
  const owners = new Map();  // session id -> authorization of its opener
  const sessionVolumes = new Map();  // session id -> volume id
  const shared = new Set();  // `${session id} ${authorization}` allowed to watch
  const watches = new Map();  // `${session id} ${authorization}` -> Set of {call, timer}
  const mayWatch = (call) => {
    const auth = call.metadata.get('authorization')[0] ?? null;
    const id = call.request.session_id;
    if (!owners.has(id)) return { code: grpc.status.NOT_FOUND, details: `no session '${id}'` };
    if (owners.get(id) === auth || shared.has(`${id} ${auth}`)) return null;
    return { code: grpc.status.PERMISSION_DENIED, details: `session '${id}' belongs to another user` };
  };
  const unary = (method, answer) => (call, callback) => {
    record(method, call);
    try {
      callback(null, answer(call.request, call));
    } catch (e) {
      callback(e);
    }
  };
  // A real 4 x 4 grey JPEG, so that the page draws it; a comment segment
  // after SOI holds the frame number, so that frames differ.
  const kGreyJpeg = Buffer.from(
    '/9j/4AAQSkZJRgABAQAAAQABAAD/2wBDABALDA4MChAODQ4SERATGCgaGBYWGDEjJR0oOjM9PDkzODdASFxOQERXRTc4' +
    'UG1RV19iZ2hnPk1xeXBkeFxlZ2P/wAALCAAEAAQBAREA/8QAHwAAAQUBAQEBAQEAAAAAAAAAAAECAwQFBgcICQoL/8QA' +
    'tRAAAgEDAwIEAwUFBAQAAAF9AQIDAAQRBRIhMUEGE1FhByJxFDKBkaEII0KxwRVS0fAkM2JyggkKFhcYGRolJicoKSo0' +
    'NTY3ODk6Q0RFRkdISUpTVFVWV1hZWmNkZWZnaGlqc3R1dnd4eXqDhIWGh4iJipKTlJWWl5iZmqKjpKWmp6ipqrKztLW2' +
    't7i5usLDxMXGx8jJytLT1NXW19jZ2uHi4+Tl5ufo6erx8vP09fb3+Pn6/9oACAEBAAA/ACv/2Q==', 'base64');
  const jpeg = (n) => Buffer.concat([kGreyJpeg.subarray(0, 2),
                                     Buffer.from([0xff, 0xfe, 0x00, 0x03, n & 0xff]),
                                     kGreyJpeg.subarray(2)]);
  const frame = (n, sequence, extra = {}) => ({
    image: jpeg(n),
    encoding: 'ENCODING_JPEG', width: 4, height: 4, last_sequence: sequence, frame_number: n,
    timings: { total_ms: 1 }, ...extra });

  const cases = makeCases(grpc, users);
  const pacs = makePacs(grpc, users, (id, auth) => (owners.has(id) && owners.get(id) === auth
    ? (loaded.get(sessionVolumes.get(id)) ?? volume).source : null));
  pacs.record = record;
  // A folder (a ZIP) comes with what a real reader says of a folder of
  // several series; a single file with nothing.
  const folderNotes = ['the folder holds 2 series; read series 2 (1.2.3.4, CT "axial", 4 ' +
                       'slices); ?series=N or ?series=UID picks another'];
  const uploads = makeUploads(grpc, users, (name, owner) => remember({
    ...volume, volume_id: `vol-${++next}`, source: `upload:${name}`, owner,
    notes: name.endsWith('.zip') ? folderNotes : [] }));
  const server = new grpc.Server();
  server.addService(Vpm.service, {
    ...cases.handlers(unary, owners, () => `ses-${++next}`),
    ...pacs.handlers(unary),
    UploadVolume: (call, callback) => {
      record('UploadVolume', call);
      uploads.take(call, callback);
    },
    ListVolumes: unary('ListVolumes', () => ({ volumes: [volume] })),
    GetVolume: unary('GetVolume', (r) => loaded.get(r.volume_id) ?? volume),
    LoadVolume: (call, callback) => {
      record('LoadVolume', call);
      const newVolume = (source) => remember({ ...volume, volume_id: `vol-${++next}`, source });
      if (call.request.source.startsWith('pacs:')) {
        pacs.load(call, callback, newVolume);
      } else {
        callback(null, newVolume(call.request.source));
      }
    },
    BuildMesh: unary('BuildMesh', (r) => ({ mesh_id: `mesh-${++next}`, volume_id: r.volume_id,
                                            stats: { vertices: 250 } })),
    RefineMesh: unary('RefineMesh', () => ({ mesh_id: `mesh-${++next}`,
                                             stats: { vertices: 400, refined: 150 } })),
    OpenSession: unary('OpenSession', (r, call) => {
      const session = { session_id: `ses-${++next}`, ...r };
      owners.set(session.session_id, call.metadata.get('authorization')[0] ?? null);
      sessionVolumes.set(session.session_id, r.volume_id);
      return cases.opened(session, call);
    }),
    CloseSession: unary('CloseSession', (r) => {
      owners.delete(r.session_id);
      cases.closed(r.session_id);
      // Its watchers' streams end as the server ends them.
      for (const [key, set] of watches) {
        if (!key.startsWith(`${r.session_id} `)) continue;
        for (const { call, timer } of set) {
          clearInterval(timer);
          call.emit('error', { code: grpc.status.FAILED_PRECONDITION,
                               details: `session '${r.session_id}' is closed` });
        }
        watches.delete(key);
      }
      return {};
    }),
    DeleteMesh: unary('DeleteMesh', () => ({})),
    ReadTransferFunction: unary('ReadTransferFunction', (r) => {
      if (r.text === 'bad') throw { code: grpc.status.INVALID_ARGUMENT, details: `file '${r.file_name}': line 7: not a number` };
      return { name: r.file_name.replace(/\.[a-z]+$/, ''),
               colors: [{ value: 0, r: 0, g: 0, b: 0 }, { value: 100, r: 1, g: 1, b: 1 }],
               opacities: [{ value: 0, opacity_per_mm: 0 }, { value: 100, opacity_per_mm: 0.5 }] };
    }),
    GetSession: unary('GetSession', (r, call) => {
      const refused = mayWatch(call);
      if (refused) throw refused;
      return { session_id: r.session_id, volume_id: 'vol-1', mesh_id: 'mesh-1' };
    }),
    Watch: (call) => {
      record('Watch', call);
      const refused = mayWatch(call);
      if (refused) {
        call.emit('error', refused);
        return;
      }
      const key = `${call.request.session_id} ${call.metadata.get('authorization')[0] ?? null}`;
      let n = 0;
      const watch = { call, timer: setInterval(() => call.write(frame(++n, 0)), 20) };
      if (!watches.has(key)) watches.set(key, new Set());
      watches.get(key).add(watch);
      call.on('cancelled', () => {
        clearInterval(watch.timer);
        watches.get(key)?.delete(watch);
      });
    },
    Interact: (call) => {
      record('Interact', call);
      let sequence = 0;
      let frames = 0;
      let slices = [];
      call.on('data', (request) => {
        calls.push({ method: 'Interact.event', request });
        const event = request.event ?? {};
        if (event.settings) slices = event.settings.slices ?? [];
        if (event.grab && event.grab.pixel_x < 0) {
          call.emit('error', { code: grpc.status.OUT_OF_RANGE,
                               details: 'grab.pixel: outside the last frame' });
          return;
        }
        if (request.session_id) call.sessionId = request.session_id;
        cases.event(call.sessionId, event);
        sequence = Math.max(sequence, Number(event.sequence) || 0);
        call.write(frame(++frames, sequence, {
          max_displacement_mm: event.drag ? 1.5 : 0,
          slices: slices.map((spec, i) => ({
            view: spec.view, image: jpeg(i), encoding: 'ENCODING_JPEG', width: 4, height: 4,
            geometry: { orientation: spec.orientation, pixel_mm: 1, offset_mm: spec.at_mm ?? 5,
                        min_offset_mm: 0, max_offset_mm: 10, origin_mm: { x: 0, y: 0, z: 5 },
                        step_u_mm: { x: 1, y: 0, z: 0 }, step_v_mm: { x: 0, y: 1, z: 0 } } })) }));
      });
      call.on('end', () => call.end());
    },
  });
  const credentials = tls
    ? grpc.ServerCredentials.createSsl(null, [{ cert_chain: tls.cert, private_key: tls.key }])
    : grpc.ServerCredentials.createInsecure();
  const port = await new Promise((resolve, reject) => server.bindAsync(
    '127.0.0.1:0', credentials, (err, p) => (err ? reject(err) : resolve(p))));
  return { address: `127.0.0.1:${port}`, calls, stop: () => server.forceShutdown(),
           keepCases: (on) => { cases.kept = on; },
           setPacs: (endpoints) => { pacs.endpoints = endpoints; },
           uploads,
           pacs,
           share: (sessionId, token) => shared.add(`${sessionId} Bearer ${token}`),
           revoke: (sessionId, token) => {
             const key = `${sessionId} Bearer ${token}`;
             shared.delete(key);
             for (const { call, timer } of watches.get(key) ?? []) {
               clearInterval(timer);
               call.emit('error', { code: grpc.status.PERMISSION_DENIED,
                                    details: `session '${sessionId}' is no longer shared with you` });
             }
             watches.delete(key);
           } };
}

// The case calls of the stand-in (see the header). sessions: session id ->
// {case_id, auth}; a case: {case_id, title, auth, events, undone, session}.
function makeCases(grpc, users) {
  const byId = new Map();
  const sessions = new Map();
  let next = 0;
  const auth = (call) => call.metadata.get('authorization')[0] ?? null;
  const userOf = (a) => users[String(a).replace(/^Bearer /, '')] ?? 'default';
  const refuse = (code, details) => Object.assign(new Error(details), { code, details });
  const kept = () => {
    if (!state.kept) {
      throw refuse(grpc.status.FAILED_PRECONDITION,
                   'this server keeps no cases (start vpm-server with --state-dir DIR)');
    }
  };
  const mine = (call, id) => {
    kept();
    const c = byId.get(id);
    if (!c || c.auth !== auth(call)) throw refuse(grpc.status.NOT_FOUND, `case '${id}' not found`);
    return c;
  };
  const info = (c) => ({ case_id: c.case_id, title: c.title, owner: userOf(c.auth), events: c.events,
                         undone: c.undone, max_displacement_mm: 1.5 * c.events, source: 'phantom:loaded',
                         created_unix_ms: 1700000000000, modified_unix_ms: 1700000000000 + c.events,
                         session_id: c.session ?? '', view: c.view ?? null });
  const state = {
    kept: false,
    opened(session, call) {
      if (!state.kept) return session;
      const c = { case_id: `case-${(++next).toString(16).padStart(8, '0')}`, title: 'phantom:loaded',
                  auth: auth(call), events: 0, undone: 0, session: session.session_id };
      byId.set(c.case_id, c);
      sessions.set(session.session_id, c);
      return { ...session, case_id: c.case_id };
    },
    closed(sessionId) {
      const c = sessions.get(sessionId);
      if (c && c.session === sessionId) c.session = null;
      sessions.delete(sessionId);
    },
    event(sessionId, event) {
      const c = sessions.get(sessionId);
      if (c && event.settings) {
        const { width, height, overlay, encoding, jpeg_quality: quality,
                interactive_quality: moving, ...view } = event.settings;
        c.view = view;
      }
      if (c && (event.grab || event.drag || event.release || event.pin || event.reset)) {
        c.events += 1;
        c.undone = 0;
      }
    },
    handlers: (unary, owners, newSessionId) => ({
      ListCases: unary('ListCases', (r, call) => {
        kept();
        return { cases: [...byId.values()].filter((c) => c.auth === auth(call)).map(info) };
      }),
      GetCase: unary('GetCase', (r, call) => info(mine(call, r.case_id))),
      OpenCase: unary('OpenCase', (r, call) => {
        const c = mine(call, r.case_id);
        if (!c.session) {
          c.session = newSessionId(c.case_id);
          owners.set(c.session, auth(call));
          sessions.set(c.session, c);
        }
        return { session_id: c.session, volume_id: 'vol-1', mesh_id: 'mesh-1', case_id: c.case_id };
      }),
      GetMesh: unary('GetMesh', (r) => ({ info: { mesh_id: r.mesh_id, volume_id: 'vol-1',
                                                  stats: { vertices: 250 } } })),
      UpdateCase: unary('UpdateCase', (r, call) => {
        const c = mine(call, r.case_id);
        if (r.title !== undefined && r.title !== null) c.title = r.title;
        return info(c);
      }),
      DeleteCase: unary('DeleteCase', (r, call) => {
        const c = mine(call, r.case_id);
        if (c.session) {
          owners.delete(c.session);
          sessions.delete(c.session);
        }
        byId.delete(c.case_id);
        return {};
      }),
      Undo: unary('Undo', (r, call) => {
        const c = sessions.get(r.session_id);
        if (!owners.has(r.session_id)) {
          throw refuse(grpc.status.NOT_FOUND, `no session '${r.session_id}'`);
        }
        if (!c) {
          throw refuse(grpc.status.FAILED_PRECONDITION,
                       'undo: this server keeps no cases (start vpm-server with --state-dir DIR)');
        }
        mine(call, c.case_id);
        const from = r.redo ? 'undone' : 'events';
        const changed = c[from] > 0;
        if (changed) {
          c[from] -= 1;
          c[r.redo ? 'events' : 'undone'] += 1;
        }
        return { changed, events: c.events, undone: c.undone, max_displacement_mm: 1.5 * c.events };
      }),
    }),
  };
  return state;
}

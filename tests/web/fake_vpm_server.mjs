// A stand-in for vpm-server in Node (grpc-js on the project's vpm.proto)
// for the gateway's own tests: it answers the calls the gateway makes,
// records each call's method, request and metadata, and streams one small
// frame per Interact event. A grab with pixel_x < 0 fails the stream with
// OUT_OF_RANGE, as the real server does for a pick outside the volume.
// Sessions belong to the bearer token that opened them: GetSession and Watch
// with another token are PERMISSION_DENIED unless the session was shared
// (share(sessionId, token)). With tls = {cert, key} it serves TLS.
import { createRequire } from 'node:module';
import path from 'node:path';

export async function startFakeServer(source, { tls = null } = {}) {
  const require = createRequire(path.join(source, 'client', 'web', 'package.json'));
  const grpc = require('@grpc/grpc-js');
  const protoLoader = require('@grpc/proto-loader');
  const definition = protoLoader.loadSync(
    path.join(source, 'proto', 'vpm', 'v2', 'vpm.proto'),
    { keepCase: true, longs: Number, enums: String, defaults: true, oneofs: true });
  const { Vpm } = grpc.loadPackageDefinition(definition).vpm.v2;

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
  const owners = new Map();  // session id -> authorization of its opener
  const shared = new Set();  // `${session id} ${authorization}` allowed to watch
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
  const frame = (n, sequence, extra = {}) => ({
    image: Buffer.from([0xff, 0xd8, n & 0xff, 0xff, 0xd9]), encoding: 'ENCODING_JPEG', width: 4,
    height: 4, last_sequence: sequence, frame_number: n, timings: { total_ms: 1 }, ...extra });

  const server = new grpc.Server();
  server.addService(Vpm.service, {
    ListVolumes: unary('ListVolumes', () => ({ volumes: [volume] })),
    GetVolume: unary('GetVolume', () => volume),
    LoadVolume: unary('LoadVolume', (r) => ({ ...volume, volume_id: `vol-${++next}`,
                                              source: r.source })),
    BuildMesh: unary('BuildMesh', (r) => ({ mesh_id: `mesh-${++next}`, volume_id: r.volume_id,
                                            stats: { vertices: 250 } })),
    RefineMesh: unary('RefineMesh', () => ({ mesh_id: `mesh-${++next}`,
                                             stats: { vertices: 400, refined: 150 } })),
    OpenSession: unary('OpenSession', (r, call) => {
      const session = { session_id: `ses-${++next}`, ...r };
      owners.set(session.session_id, call.metadata.get('authorization')[0] ?? null);
      return session;
    }),
    CloseSession: unary('CloseSession', (r) => {
      owners.delete(r.session_id);
      return {};
    }),
    DeleteMesh: unary('DeleteMesh', () => ({})),
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
      call.write(frame(1, 0));
    },
    Interact: (call) => {
      record('Interact', call);
      let sequence = 0;
      let frames = 0;
      call.on('data', (request) => {
        calls.push({ method: 'Interact.event', request });
        const event = request.event ?? {};
        if (event.grab && event.grab.pixel_x < 0) {
          call.emit('error', { code: grpc.status.OUT_OF_RANGE,
                               details: 'grab.pixel: outside the last frame' });
          return;
        }
        sequence = Math.max(sequence, Number(event.sequence) || 0);
        call.write(frame(++frames, sequence, { max_displacement_mm: event.drag ? 1.5 : 0 }));
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
           share: (sessionId, token) => shared.add(`${sessionId} Bearer ${token}`) };
}

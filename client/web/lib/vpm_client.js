// The gateway's side of the vpm API: loads the project's own
// proto/vpm/v3/vpm.proto with @grpc/proto-loader and wraps the unary calls
// as promises. Each call carries the token of the signed-in user it is made
// for as `authorization: Bearer TOKEN` metadata, so the server knows who is
// calling; the token never goes back to a browser. TLS towards the server
// when given a CA (and, for mutual TLS, a client certificate and key).
//
// Each signed-in user gets a channel (an HTTP/2 connection) of their own
// (user_channels.js): a call of one user that stalls its connection (a
// status the server cannot send, a flow-control window never opened) stalls
// only that user's calls and streams, never another user's.
import path from 'node:path';
import { fileURLToPath } from 'node:url';

import grpc from '@grpc/grpc-js';
import protoLoader from '@grpc/proto-loader';

import { UserChannels } from './user_channels.js';

const here = path.dirname(fileURLToPath(import.meta.url));
export const kDefaultProtoPath = path.resolve(here, '../../../proto/vpm/v3/vpm.proto');

// Field names stay snake_case as in the proto (keepCase), 64-bit integers
// become JS numbers (sequences and sizes stay far below 2^53), unset
// scalars come back as their defaults, and a oneof reports which member is set.
const kLoaderOptions = {
  keepCase: true,
  longs: Number,
  enums: String,
  defaults: true,
  oneofs: true,
};

// grpc-js backs off up to 120 s between reconnection attempts by default;
// a viewer wants to see a restarted server within seconds. grpc-js shares
// one connection between channels of equal target and options (its global
// subchannel pool) unless told not to: each user's channel has its own.
const kChannelOptions = {
  'grpc.initial_reconnect_backoff_ms': 250,
  'grpc.min_reconnect_backoff_ms': 250,
  'grpc.max_reconnect_backoff_ms': 3000,
  'grpc.max_receive_message_length': 64 * 1024 * 1024,
  'grpc.use_local_subchannel_pool': 1,
};

// Deadlines of the unary calls, ms. Mesh building and session opening run
// the proxy-mesh build and the FEM set-up on the server, which takes seconds
// on lavapipe for a 256^3 volume.
const kDeadlineMs = {
  ListVolumes: 5000,
  GetVolume: 5000,
  LoadVolume: 120000,
  BuildMesh: 120000,
  RefineMesh: 120000,
  OpenSession: 120000,
  OpenCase: 120000,  // loads the volume, builds the mesh and replays the case
  ListCases: 10000,
  CloseSession: 5000,
  DeleteMesh: 5000,
  ReadTransferFunction: 10000,
  ListPacsEndpoints: 5000,
  // QIDO-RS through vpm-server, which ends a PACS transfer stalled for 60 s.
  SearchStudies: 90000,
  ListSeries: 90000,
  ListDataRoot: 10000,
  GetLoadProgress: 5000,
  // The gateway's spooled file at disk speed, then the server's read of it
  // (a DICOM archive of a large series takes a while).
  UploadVolume: 600000,
};

export class VpmClient {
  // address: HOST:PORT of vpm-server; protoPath: vpm.proto; tls: null for
  // plaintext, else {ca, cert, key} (PEM Buffers; cert and key for mutual
  // TLS, may be null).
  constructor({ address, protoPath = kDefaultProtoPath, tls = null }) {
    // vpm.proto imports vpm/v3/pacs.proto: imports resolve from the folder
    // above vpm/v3.
    this.definition = protoLoader.loadSync(
      protoPath, { ...kLoaderOptions, includeDirs: [path.resolve(path.dirname(protoPath), '../..')] });
    const { Vpm } = grpc.loadPackageDefinition(this.definition).vpm.v3;
    this.address = address;
    const credentials = tls ? grpc.credentials.createSsl(tls.ca, tls.key ?? null, tls.cert ?? null)
                            : grpc.credentials.createInsecure();
    this.channels = new UserChannels(() => new Vpm(address, credentials, kChannelOptions));
  }

  // affinity: a key for `x-vpm-session`, on which a consistent-hash router
  // (HAProxy in docker/) picks the replica; every call of one browser tab
  // carries the same key, so its volume, mesh, session and stream stay on
  // one server.
  // as: {token, affinity}: the user's bearer token ('' for a server
  // started with --no-auth) and the tab's affinity key.
  metadata({ token = '', affinity = '' } = {}) {
    const md = new grpc.Metadata();
    if (token) md.set('authorization', `Bearer ${token}`);
    if (affinity) md.set('x-vpm-session', affinity);
    return md;
  }

  // A tab of the user `as.token` starts (acquire) or ends (release): the
  // user's channel lives while they have tabs, and a little after.
  acquire(as = {}) {
    this.channels.acquire(as.token ?? '');
  }

  release(as = {}) {
    this.channels.release(as.token ?? '');
  }

  // The stub on the channel of the user `as.token`.
  stub(as = {}) {
    return this.channels.stub(as.token ?? '');
  }

  // One unary call as `as` (metadata()): resolves with the response,
  // rejects with the gRPC error (err.code, err.details).
  // A call that ran out its deadline or was refused a stream renews the
  // user's channel (user_channels.js). `pending`, a Set, holds the call
  // while it runs, so that its owner can cancel it (a tab closing, a
  // sign-out): the server then stops the work (a mesh build, a load).
  // deadlineMs: this call's own deadline (a PACS load), else the method's.
  call(method, request, as = {}, pending = null, deadlineMs = null) {
    const deadline = new Date(Date.now() + (deadlineMs ?? kDeadlineMs[method] ?? 30000));
    const stub = this.stub(as);
    return new Promise((resolve, reject) => {
      const call = stub[method](request, this.metadata(as), { deadline }, (err, response) => {
        pending?.delete(call);
        if (err && connectionStuck(err)) this.channels.renew(as.token ?? '', stub);
        if (err) reject(err);
        else resolve(response);
      });
      pending?.add(call);
    });
  }

  // The bidirectional Interact stream (events in, frames out).
  interact(as = {}) {
    return this.stub(as).Interact(this.metadata(as));
  }

  // The Watch stream of a session (frames out): for a viewer it is shared with.
  watch(request, as = {}) {
    return this.stub(as).Watch(request, this.metadata(as));
  }

  // The ExportDicom stream (progress parts, then a summary), ending within
  // deadlineMs.
  exportDicom(request, as = {}, deadlineMs = 600000) {
    return this.stub(as).ExportDicom(request, this.metadata(as),
                                     { deadline: new Date(Date.now() + deadlineMs) });
  }

  // The UploadVolume client stream as `as` (header first, then chunks;
  // the gateway's lib/volume_upload.js writes them); callback(err, VolumeInfo).
  uploadVolume(as, callback) {
    return this.stub(as).UploadVolume(this.metadata(as), { deadline: new Date(
      Date.now() + kDeadlineMs.UploadVolume) }, callback);
  }

  close() {
    this.channels.closeAll();
  }
}

// The name of a gRPC status code, e.g. 14 -> "UNAVAILABLE".
export function statusName(code) {
  const name = Object.keys(grpc.status).find((k) => grpc.status[k] === code);
  return name ?? `code ${code}`;
}

// The error of a stream the gateway did not cancel itself. A balancer that
// loses the vpm-server replica behind a stream resets it (grpc-js: CANCELLED
// "Call cancelled") or ends it without gRPC trailers (UNKNOWN "No status
// received"): either is returned as UNAVAILABLE saying so; other errors
// unchanged.
export function streamError(err) {
  const cut = err?.code === grpc.status.CANCELLED ||
    (err?.code === grpc.status.UNKNOWN && /No status received/.test(err?.details ?? ''));
  if (!cut) return err;
  return Object.assign(new Error('replica lost'), {
    code: grpc.status.UNAVAILABLE,
    details: 'the stream ended without a status: the vpm-server replica behind the balancer ' +
             'went away',
  });
}

// True for errors that say more of the call's connection than of the
// server: no answer within the deadline, or a stream refused (HTTP/2
// REFUSED_STREAM, a connection whose streams are all held).
function connectionStuck(err) {
  return err?.code === grpc.status.DEADLINE_EXCEEDED ||
    (err?.code === grpc.status.UNAVAILABLE && /Stream refused/i.test(err?.details ?? ''));
}

// True for errors that mean "the server is not there", as opposed to a call
// the server refused.
export function isServerDown(err) {
  return err?.code === grpc.status.UNAVAILABLE || err?.code === grpc.status.DEADLINE_EXCEEDED;
}

export const GrpcStatus = grpc.status;

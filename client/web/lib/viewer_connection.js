// One browser tab: its WebSocket, the session it opened on vpm-server and
// the Interact stream that carries its events and frames.
//
// Browser -> gateway, JSON text messages:
//   {type: 'list'}                               -> {type: 'volumes', volumes}
//   {type: 'open', source | volume_id, settings, camera}
//        LoadVolume (or reuse of a loaded volume with the same source),
//        BuildMesh, OpenSession, then Interact -> progress..., {type: 'opened'}
//   {type: 'event', event: ClientEvent}          written to the Interact stream
//   {type: 'refine', point_mm}                   RefineMesh + a session on the new mesh
// Gateway -> browser:
//   binary: one frame (lib/frame_packet.js)
//   {type: 'hello'|'server'|'volumes'|'progress'|'opened'|'refined'|'stream'|
//          'session_lost'|'error', ...}
// The camera is the session's on the server, render settings the stream's:
// the gateway remembers the last of each the browser sent and replays them
// on every new stream, so reconnecting and refining keep the view. Replays
// carry the browser's last sequence, so frames of the new stream report
// what the browser has sent as shown.
import crypto from 'node:crypto';

import { Backoff } from '../public/backoff.js';
import { explainError } from './explain_error.js';
import { packFrame } from './frame_packet.js';
import { toProtoSettings } from './render_settings.js';
import { GrpcStatus, isServerDown, statusName, streamError } from './vpm_client.js';

// Stream restarts after an event error that get no frame before failing
// again: past this many the gateway waits for the browser's next event.
const kMaxBarrenRestarts = 3;

export class ViewerConnection {
  // ws: a `ws` WebSocket; client: a VpmClient; log: (line) => void.
  constructor({ ws, client, log = () => {} }) {
    Object.assign(this, { ws, client, log });
    this.affinity = crypto.randomUUID();  // x-vpm-session of every call of this tab
    this.volume = null;
    this.mesh = null;
    this.session = null;
    this.settings = null;   // last RenderSettings the browser sent
    this.camera = null;     // last Camera the browser sent
    this.lastSequence = 0;  // newest event sequence the browser sent
    this.call = null;       // the Interact call
    this.streamGen = 0;     // ignores callbacks of replaced streams
    this.barrenRestarts = 0;
    this.openOp = 0;        // the newest open/refine wins
    this.serverUp = null;
    this.probeBackoff = new Backoff({ firstMs: 500, maxMs: 5000 });
    this.probeTimer = null;
    this.sending = false;   // a frame is being written to the WebSocket
    this.pending = null;    // the newest frame waiting for it
    this.dropped = 0;       // frames the gateway replaced before sending
    this.closed = false;

    // An error nothing else caught ends this connection only, with a message;
    // the gateway and every other tab carry on.
    ws.on('message', (data, isBinary) => this.onMessage(data, isBinary).catch((e) => {
      this.log(`closing a connection after an unexpected error: ${e?.stack ?? e}`);
      this.send({ type: 'error', what: 'gateway', message: `internal error: ${e?.message ?? e}` });
      this.ws.close(1011, 'internal error');
    }));
    ws.on('close', () => this.onClose());
    this.send({ type: 'hello', server: client.address });
    this.probe();
  }

  rpc(method, request) {
    return this.client.call(method, request, this.affinity);
  }

  send(message) {
    if (!this.closed && this.ws.readyState === this.ws.OPEN) this.ws.send(JSON.stringify(message));
  }

  fail(what, err) {
    const message = explainError(err, what, this.client.address);
    this.log(`${what}: ${statusName(err?.code)}: ${err?.details ?? err}`);
    this.send({ type: 'error', what, code: statusName(err?.code), message });
    if (isServerDown(err)) this.serverDown(err);
  }

  async onMessage(data, isBinary) {
    let message;
    try {
      if (isBinary) throw new Error('binary messages are not accepted');
      message = JSON.parse(data.toString('utf8'));
      if (message === null || typeof message !== 'object' || Array.isArray(message)) {
        throw new Error('a message is a JSON object with a "type"');
      }
    } catch (e) {
      this.send({ type: 'error', what: 'message', message: `bad message: ${e.message}` });
      return;
    }
    switch (message.type) {
      case 'list': return this.listVolumes();
      case 'open': return this.open(message);
      case 'event': return this.event(message.event);
      case 'refine': return this.refine(message.point_mm);
      default:
        this.send({ type: 'error', what: 'message', message: `unknown message type '${message.type}'` });
    }
  }

  // ------------------------------------------------------------ server state

  // Asks the server for its volumes: tells the browser whether it is up,
  // and keeps asking with backoff while it is not.
  async probe() {
    clearTimeout(this.probeTimer);
    this.probeTimer = null;
    if (this.closed) return;
    try {
      const { volumes } = await this.rpc('ListVolumes', {});
      this.serverUpAgain();
      this.send({ type: 'volumes', volumes });
    } catch (err) {
      if (isServerDown(err)) this.serverDown(err);
      else this.fail('Listing volumes', err);
    }
  }

  serverDown(err) {
    if (this.closed) return;
    if (this.serverUp !== false) {
      this.serverUp = false;
      this.send({ type: 'server', up: false,
                  message: explainError(err, null, this.client.address) });
    }
    if (this.probeTimer === null) {
      this.probeTimer = setTimeout(() => this.probe(), this.probeBackoff.next());
    }
  }

  serverUpAgain() {
    this.probeBackoff.reset();
    if (this.serverUp === true) return;
    const wasDown = this.serverUp === false;
    this.serverUp = true;
    this.send({ type: 'server', up: true, address: this.client.address });
    // Back after an outage: the session may have survived (a network blip)
    // or not (a restart); the stream tells which.
    if (wasDown && this.session && !this.call) this.startStream();
  }

  async listVolumes() {
    try {
      const { volumes } = await this.rpc('ListVolumes', {});
      this.serverUpAgain();
      this.send({ type: 'volumes', volumes });
    } catch (err) {
      this.fail('Listing volumes', err);
    }
  }

  // ------------------------------------------------------------ sessions

  async open({ source, volume_id: volumeId, settings, camera }) {
    const op = ++this.openOp;
    this.stopStream();
    this.closeSession(this.session);
    this.session = null;
    if (settings) this.settings = settings;
    this.camera = camera ?? null;
    const what = volumeId ? `Opening volume ${volumeId}` : `Loading ${source}`;
    try {
      this.send({ type: 'progress', step: 'volume', text: `${what} ...` });
      const volume = volumeId ? await this.rpc('GetVolume', { volume_id: volumeId })
                              : await this.loadOrReuse(source);
      if (op !== this.openOp) return;
      this.send({ type: 'progress', step: 'mesh', text: 'Building the proxy mesh ...' });
      const mesh = await this.rpc('BuildMesh', { volume_id: volume.volume_id });
      if (op !== this.openOp) return;
      this.send({ type: 'progress', step: 'session', text: 'Opening a session ...' });
      const session = await this.rpc('OpenSession', {
        volume_id: volume.volume_id, mesh_id: mesh.mesh_id });
      if (op !== this.openOp || this.closed) {
        this.closeSession(session);
        return;
      }
      Object.assign(this, { volume, mesh, session });
      this.serverUpAgain();
      this.send({ type: 'opened', volume, mesh, session });
      this.startStream();
    } catch (err) {
      if (op === this.openOp) this.fail(what, err);
    }
  }

  async loadOrReuse(source) {
    if (!source) throw Object.assign(new Error('no source given'), { details: 'source: required' });
    const { volumes } = await this.rpc('ListVolumes', {});
    return volumes.find((v) => v.source === source) ??
      await this.rpc('LoadVolume', { source });
  }

  // RefineMesh makes a new mesh (meshes are immutable), so the view moves to
  // a new session on it; the old session and its deformation are closed.
  async refine(pointMm) {
    if (!this.session) {
      this.send({ type: 'error', what: 'Refine', message: 'Refine: open a volume first.' });
      return;
    }
    const op = ++this.openOp;
    const what = 'Refining the mesh';
    try {
      this.send({ type: 'progress', step: 'refine', text: `${what} ...` });
      const mesh = await this.rpc('RefineMesh', {
        mesh_id: this.mesh.mesh_id, point_mm: pointMm });
      if (op !== this.openOp) return;
      const session = await this.rpc('OpenSession', {
        volume_id: this.volume.volume_id, mesh_id: mesh.mesh_id });
      if (op !== this.openOp || this.closed) {
        this.closeSession(session);
        return;
      }
      const old = this.session;
      Object.assign(this, { mesh, session });
      this.send({ type: 'refined', mesh, session, point_mm: pointMm });
      this.startStream();
      this.closeSession(old);
    } catch (err) {
      if (op === this.openOp) this.fail(what, err);
    }
  }

  closeSession(session) {
    if (!session) return;
    this.rpc('CloseSession', { session_id: session.session_id })
      .catch((err) => this.log(`CloseSession ${session.session_id}: ${err.details ?? err}`));
  }

  // ------------------------------------------------------------ the stream

  startStream() {
    this.stopStream();
    const gen = ++this.streamGen;
    const call = this.client.interact(this.affinity);
    this.call = call;
    let framed = false;
    call.on('data', (frame) => {
      if (gen !== this.streamGen) return;
      if (!framed) {
        framed = true;
        this.barrenRestarts = 0;
        this.serverUpAgain();
      }
      this.deliver(frame);
    });
    call.on('error', (err) => {
      // Streams the gateway cancels are replaced first (streamGen moved on).
      if (gen === this.streamGen) this.onStreamError(streamError(err), framed);
    });
    call.on('end', () => {
      if (gen === this.streamGen) this.call = null;
    });
    const sequence = this.lastSequence;
    call.write({ session_id: this.session.session_id,
                 event: { sequence, settings: toProtoSettings(this.settings) } });
    if (this.camera) call.write({ event: { sequence, camera: this.camera } });
    this.send({ type: 'stream', state: 'open', session_id: this.session.session_id });
  }

  stopStream() {
    this.streamGen += 1;
    if (this.call) this.call.cancel();
    this.call = null;
    this.pending = null;
  }

  onStreamError(err, framed) {
    this.call = null;
    this.send({ type: 'stream', state: 'closed', code: statusName(err.code) });
    if (isServerDown(err)) {
      this.serverDown(err);
      return;
    }
    const gone = err.code === GrpcStatus.NOT_FOUND ||
      (err.code === GrpcStatus.FAILED_PRECONDITION && /session.*closed/.test(err.details ?? ''));
    if (gone) {
      // A restarted server, or an idle session the server expired.
      this.session = null;
      this.send({ type: 'session_lost',
                  message: `The session is gone from vpm-server (${err.details}); reopening.` });
      return;
    }
    // An event the server refused (e.g. a grab outside the volume) ends the
    // stream; the session is intact, so a new stream carries on.
    this.fail('Interaction', err);
    this.barrenRestarts = framed ? 0 : this.barrenRestarts + 1;
    if (this.session && this.barrenRestarts <= kMaxBarrenRestarts) this.startStream();
  }

  event(event) {
    if (!event || typeof event !== 'object') {
      this.send({ type: 'error', what: 'Event', message: 'event: missing' });
      return;
    }
    this.lastSequence = Math.max(this.lastSequence, Number(event.sequence) || 0);
    if (event.settings) this.settings = event.settings;
    if (event.camera) this.camera = event.camera;
    if (!this.session) {
      // Camera and settings still count for the next stream.
      if (!event.settings && !event.camera) {
        this.send({ type: 'error', what: 'Event', message: 'No session: open a volume first.' });
      }
      return;
    }
    if (!this.call) {
      // While the server is down the probe reopens the stream; events
      // meanwhile would only fail again (the page already says why).
      if (this.serverUp === false) return;
      this.barrenRestarts = 0;
      this.startStream();
      if (event.settings || event.camera) return;  // replayed by startStream
    }
    this.call.write({ event: event.settings ? { ...event, settings: toProtoSettings(event.settings) }
                                            : event });
  }

  // Newest frame wins: one frame in flight on the WebSocket, a newer one
  // replaces the one waiting.
  deliver(frame) {
    if (this.sending) {
      if (this.pending) this.dropped += 1;
      this.pending = frame;
      return;
    }
    this.sendFrame(frame);
  }

  sendFrame(frame) {
    if (this.closed || this.ws.readyState !== this.ws.OPEN) return;
    this.sending = true;
    this.ws.send(packFrame(frame, { gateway_dropped: this.dropped }), { binary: true }, () => {
      this.sending = false;
      const next = this.pending;
      this.pending = null;
      if (next) this.sendFrame(next);
    });
  }

  onClose() {
    this.closed = true;
    this.openOp += 1;
    clearTimeout(this.probeTimer);
    this.stopStream();
    this.closeSession(this.session);
    this.session = null;
  }
}

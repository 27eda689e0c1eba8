// One browser tab of a signed-in user: its WebSocket, the session it opened
// on vpm-server (as that user: every call carries the user's token) and the
// Interact stream that carries its events and frames. When the tab goes,
// its session is closed and the meshes it built are deleted (one a session
// of another tab still uses stays: the server refuses to delete it).
//
// Browser -> gateway, JSON text messages (validate_message.js checks each;
// a bad one is answered with an error and changes nothing):
//   {type: 'list'}                               -> {type: 'volumes', volumes}
//   {type: 'open', source | volume_id, settings, camera, sequence}
//        LoadVolume (or reuse of a loaded volume with the same source),
//        BuildMesh (the server returns its mesh of equal parameters),
//        OpenSession, then Interact -> progress..., {type: 'opened'}
//   {type: 'event', event: ClientEvent}          written to the Interact stream
//   {type: 'refine', point_mm}                   RefineMesh + a session on the new mesh
//   {type: 'watch', session_id, settings}        Watch another user's session
//        that its owner shared with this user (frames only; events refused)
//   {type: 'tf', file_name, text, preset}        ReadTransferFunction (a ParaView
//        .json or Slicer .vp the user picked) -> {type: 'tf', name, colors,
//        opacities}; settings with `uploaded_tf: true` then render with it
//   {type: 'open_case', case_id, settings, camera, sequence}
//        OpenCase (the case's open session, or a new one with its events
//        replayed), GetVolume, GetMesh, then Interact -> {type: 'opened'};
//        opened afresh (no camera: not the page carrying on), GetCase too,
//        and the case's kept view (pageView) replaces the page's settings
//        and comes in opened.view for the page's controls
//   {type: 'cases'|'rename_case'|'delete_case'|'undo', ...}   case_calls.js
//   {type: 'pacs_endpoints'|'pacs_search'|'pacs_series'|'pacs_open'|'pacs_cancel'|
//         'pacs_thumbnail', ...}   pacs_calls.js (the Studies panel)
//   {type: 'data_ls', path}   data_root_calls.js (the Server files section)
//   {type: 'export_dicom', endpoint, series_description}   dicom_export_call.js
// A volume file comes by POST /upload naming this tab (volume_upload.js);
// its progress comes here as upload_progress, and the page then opens the
// new volume with 'open' {volume_id}.
// Gateway -> browser:
//   binary: one frame (lib/frame_packet.js)
//   {type: 'hello'|'server'|'volumes'|'progress'|'opened'|'refined'|'stream'|
//          'session_lost'|'tf'|'cases'|'case_renamed'|'case_deleted'|'undone'|
//          'pacs_endpoints'|'pacs_studies'|'pacs_series'|'pacs_progress'|
//          'pacs_loaded'|'pacs_thumbnail'|'export_progress'|'exported'|'pacs_error'|
//          'upload_progress'|'data_listing'|'data_error'|'error', ...}
//   hello: {server, tab_id, max_upload_bytes}: tab_id names this tab in an upload
// With --state-dir on the server every session is a case: `opened` and
// `refined` carry it (session.case_id), and the page reopens it by id when
// the session is lost (a server restart) or the gateway comes back.
// The camera is the session's on the server, render settings the stream's:
// the gateway remembers the last of each the browser sent and replays them
// on every new stream, so reconnecting and refining keep the view. Replays
// carry the browser's last sequence (an open carries it too: a new gateway
// learns it), so frames of the new stream report what the browser has sent
// as shown.
import crypto from 'node:crypto';

import { Backoff } from '../public/backoff.js';
import { CaseCalls } from './case_calls.js';
import { DicomExport } from './dicom_export_call.js';
import { explainError } from './explain_error.js';
import { packFrame } from './frame_packet.js';
import { DataRootCalls } from './data_root_calls.js';
import { PacsCalls } from './pacs_calls.js';
import { pageView, toProtoSettings, withCaseView } from './render_settings.js';
import { SessionRecord } from './session_record.js';
import { parseMessage } from './validate_message.js';
import { GrpcStatus, isServerDown, statusName, streamError } from './vpm_client.js';

// Stream restarts after an event error that get no frame before failing
// again: past this many the gateway waits for the browser's next event.
const kMaxBarrenRestarts = 3;
// DeleteMesh attempts after FAILED_PRECONDITION (100 ms doubling: 3.1 s in all).
const kDeleteMeshRetries = 5;
// The API's default view (distance 0: fit the volume), which a reset
// OrbitCamera of the page reproduces: a case opened without the page's
// camera starts there, so that page and server agree on the view.
const kDefaultCamera = { azimuth_deg: 0, elevation_deg: 0, distance_mm: 0,
                         pan_mm: { x: 0, y: 0, z: 0 } };

export class ViewerConnection {
  // ws: a `ws` WebSocket; client: a VpmClient; shape: a ProtoShape of the
  // client's proto; meshRefs: the gateway's MeshRefs; token: the signed-in
  // user's token ('' for a server without auth); user: their name; record:
  // the gateway's SessionRecord; log: (line) => void; maxUploadBytes: the
  // gateway's upload cap, told to the page.
  constructor({ ws, client, shape, meshRefs, token = '', user = '', record = new SessionRecord(),
                log = () => {}, maxUploadBytes = 0 }) {
    Object.assign(this, { ws, client, shape, meshRefs, user, record, log });
    // Names this tab in POST /upload (with the user's cookie): the upload
    // goes as this tab's user, with its x-vpm-session key.
    this.tabId = crypto.randomBytes(16).toString('base64url');
    // Every call of this tab: the user's token and one x-vpm-session key,
    // on the user's own channel.
    this.as = { token, affinity: crypto.randomUUID() };
    this.client.acquire(this.as);
    // Sessions an earlier gateway process left open for this user are
    // closed before this tab opens one (they would count against the cap).
    this.leftoversClosed = record.closeLeftovers(user, (id) =>
      this.rpc('CloseSession', { session_id: id }).then(() => true, (err) => !isServerDown(err)));
    this.watching = false;  // the session is another user's, shared to watch
    this.serverUser = null; // this user's name on the server (SessionInfo.owner), once seen
    this.builtMeshes = new Map();  // mesh id -> {volumeId, holds}: built or refined here
    this.volume = null;
    this.mesh = null;
    this.session = null;
    this.settings = null;   // last RenderSettings the browser sent
    this.uploadedTf = null; // RenderTransferFunction of the browser's last 'tf'
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
    this.calls = new Set();  // unary calls running (grpc-js call objects)
    this.cases = new CaseCalls(this);
    this.pacs = new PacsCalls(this);
    this.dataRoot = new DataRootCalls(this);
    this.dicomExport = new DicomExport(this);

    // An error nothing else caught ends this connection only, with a message;
    // the gateway and every other tab carry on.
    const unexpected = (e) => {
      this.log(`closing a connection after an unexpected error: ${e?.stack ?? e}`);
      this.send({ type: 'error', what: 'gateway', message: `internal error: ${e?.message ?? e}` });
      this.ws.close(1011, 'internal error');
    };
    ws.on('message', (data, isBinary) => {
      try {
        this.onMessage(data, isBinary).catch(unexpected);
      } catch (e) {
        unexpected(e);
      }
    });
    // A frame ws cannot accept (bad UTF-8, too large, bad opcode): ws closes
    // the socket with the matching code after this.
    ws.on('error', (e) => this.log(`WebSocket error: ${e.message}`));
    ws.on('close', () => this.onClose());
    this.send({ type: 'hello', server: client.address, tab_id: this.tabId,
                max_upload_bytes: maxUploadBytes });
    this.probe();
  }

  // A unary call of this tab's; cancelled if still running when the tab
  // closes (onClose).
  rpc(method, request) {
    return this.client.call(method, request, this.as, this.closed ? null : this.calls);
  }

  // A call (anything with cancel()) of this tab's that runs past an await:
  // cancelled when the tab closes (onClose), or at once if it already has.
  // The caller deletes it from this.calls when it ends.
  track(call) {
    this.calls.add(call);
    if (this.closed) call.cancel();
  }

  send(message) {
    if (!this.closed && this.ws.readyState === this.ws.OPEN) this.ws.send(JSON.stringify(message));
  }

  // extra: more fields for the page (e.g. the case_id an open_case failed on).
  fail(what, err, extra = {}) {
    const message = explainError(err, what, this.client.address);
    this.log(`${what}: ${statusName(err?.code)}: ${err?.details ?? err}`);
    this.send({ type: 'error', what, code: statusName(err?.code), message, ...extra });
    if (isServerDown(err)) this.serverDown(err);
  }

  async onMessage(data, isBinary) {
    let message;
    try {
      message = parseMessage(this.shape, data, isBinary);
    } catch (e) {
      this.send({ type: 'error', what: 'message', message: `bad message: ${e.message}` });
      return;
    }
    switch (message.type) {
      case 'list': return this.listVolumes();
      case 'open': return this.open(message);
      case 'watch': return this.watch(message);
      case 'event': return this.event(message.event);
      case 'refine': return this.refine(message.point_mm);
      case 'tf': return this.readTransferFunction(message);
      case 'open_case': return this.openCase(message);
      case 'cases': return this.cases.list();
      case 'rename_case': return this.cases.rename(message);
      case 'delete_case': return this.cases.delete(message);
      case 'undo': return this.cases.undo(message);
      case 'pacs_endpoints': return this.pacs.endpoints();
      case 'pacs_search': return this.pacs.search(message);
      case 'pacs_series': return this.pacs.series(message);
      case 'pacs_open': return this.pacs.open(message);
      case 'pacs_cancel': return this.pacs.cancelLoad();
      case 'pacs_thumbnail': return this.pacs.thumbnail(message);
      case 'data_ls': return this.dataRoot.list(message);
      case 'export_dicom': return this.dicomExport.start(message);
      default: throw new Error(`message type ${message.type} passed the check`);
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

  // fromStream: the stream's first frame says so (that stream is fine).
  serverUpAgain(fromStream = false) {
    this.probeBackoff.reset();
    if (this.serverUp === true) return;
    const wasDown = this.serverUp === false;
    this.serverUp = true;
    this.send({ type: 'server', up: true, address: this.client.address });
    // Back after an outage: the session may have survived (a network blip)
    // or not (a restart); the stream tells which. A stream still open then
    // is on a connection that stopped answering: it is replaced.
    if (wasDown && this.session && !(fromStream && this.call)) this.startStream();
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

  async open({ source, volume_id: volumeId, settings, camera, sequence }) {
    const op = ++this.openOp;
    this.lastSequence = Math.max(this.lastSequence, sequence ?? 0);
    this.stopStream();
    this.releaseSession();
    if (settings) this.settings = settings;
    this.camera = camera ?? null;
    const what = volumeId ? `Opening volume ${volumeId}` : `Loading ${source}`;
    try {
      this.send({ type: 'progress', step: 'volume', text: `${what} ...` });
      const volume = volumeId ? await this.rpc('GetVolume', { volume_id: volumeId })
                              : await this.loadOrReuse(source);
      if (op !== this.openOp) return;
      this.send({ type: 'progress', step: 'mesh', text: 'Building the proxy mesh ...' });
      let mesh = await this.buildMesh(volume);
      if (op !== this.openOp) return;
      this.send({ type: 'progress', step: 'session', text: 'Opening a session ...' });
      let session;
      try {
        session = await this.openSession(volume, mesh);
      } catch (err) {
        // Another tab deleted the (shared) mesh between our BuildMesh and
        // this call: build it again, once.
        if (err?.code !== GrpcStatus.NOT_FOUND || !/mesh/.test(err.details ?? '')) throw err;
        mesh = await this.buildMesh(volume);
        session = await this.openSession(volume, mesh);
      }
      if (op !== this.openOp || this.closed) {
        this.closeSession(session, mesh);
        return;
      }
      Object.assign(this, { volume, mesh, session, watching: false });
      this.serverUpAgain();
      this.send({ type: 'opened', volume, mesh, session });
      this.startStream();
    } catch (err) {
      if (op === this.openOp) this.fail(what, err);
    }
  }

  // OpenSession as this tab's user, once an earlier gateway's leftovers are
  // closed; the session is recorded until closed (session_record.js).
  async openSession(volume, mesh) {
    await this.leftoversClosed;
    const session = await this.rpc('OpenSession', { volume_id: volume.volume_id,
                                                    mesh_id: mesh.mesh_id });
    this.record.opened(this.user, session.session_id);
    if (session.owner) this.serverUser = session.owner;
    return session;
  }

  async buildMesh(volume) {
    await this.meshRefs.quiet(volume.volume_id);
    const done = this.meshRefs.build(volume.volume_id);
    try {
      const mesh = await this.rpc('BuildMesh', { volume_id: volume.volume_id });
      this.holdMesh(mesh);
      return mesh;
    } finally {
      done();
    }
  }

  // This tab uses `mesh` (a hold per BuildMesh or RefineMesh answer).
  holdMesh(mesh) {
    this.meshRefs.hold(mesh.mesh_id);
    const mine = this.builtMeshes.get(mesh.mesh_id) ?? { volumeId: mesh.volume_id, holds: 0 };
    mine.holds += 1;
    this.builtMeshes.set(mesh.mesh_id, mine);
  }

  // OpenCase as this tab's user: the case's open session (this tab's own
  // when it already shows the case) or a new one with its events replayed;
  // then its volume and mesh for the page, and the stream. `camera`: the
  // page's (reattaching to the case it showed), else the default view.
  async openCase({ case_id: caseId, settings, camera, sequence }) {
    const op = ++this.openOp;
    this.lastSequence = Math.max(this.lastSequence, sequence ?? 0);
    const same = !this.watching && this.session?.case_id === caseId;
    // Opened afresh (not the page carrying on with its own camera and
    // settings): the case's kept view replaces the page's.
    const fresh = !same && !camera;
    this.stopStream();
    if (!same) this.releaseSession();
    if (settings) this.settings = settings;
    this.camera = camera ?? kDefaultCamera;
    const what = `Opening case ${caseId}`;
    try {
      this.send({ type: 'progress', step: 'case', text: `${what} ...` });
      await this.leftoversClosed;
      const session = await this.rpc('OpenCase', { case_id: caseId });
      this.record.opened(this.user, session.session_id);
      if (session.owner) this.serverUser = session.owner;
      if (op !== this.openOp || this.closed) {
        if (!same) this.closeSession(session);
        return;
      }
      Object.assign(this, { session, watching: false });
      const [volume, mesh, view] = await Promise.all([
        this.rpc('GetVolume', { volume_id: session.volume_id }),
        this.caseMesh(session),
        fresh ? this.caseView(caseId) : null]);
      if (op !== this.openOp || this.closed) return;
      Object.assign(this, { volume, mesh });
      if (view) this.takeCaseView(view);
      this.serverUpAgain();
      this.send({ type: 'opened', volume, mesh, session, ...(view ? { view } : {}) });
      this.startStream();
    } catch (err) {
      if (op === this.openOp) this.fail(what, err, { case_id: caseId });
    }
  }

  // The case's kept view in the page's names (pageView), or null: none
  // kept, or GetCase failed (the case then opens on the page's settings).
  async caseView(caseId) {
    const info = await this.rpc('GetCase', { case_id: caseId }).catch(() => null);
    return pageView(info?.view);
  }

  // The stream starts with the case's view (withCaseView); its own transfer
  // function becomes this tab's upload, which the page is told of as one.
  takeCaseView(view) {
    this.settings = withCaseView(this.settings, view);
    const tf = view.render_tf;
    if (!tf) return;
    this.uploadedTf = tf;
    this.send({ type: 'tf', name: tf.name, colors: tf.colors.length,
                opacities: tf.opacities.length });
  }

  // The mesh OpenCase built (or its open session uses), held by this tab as
  // a mesh it built (deleted when unused once the tab goes); its id alone
  // when GetMesh fails (the page then shows no mesh statistics).
  async caseMesh(session) {
    const fallback = { mesh_id: session.mesh_id, volume_id: session.volume_id };
    const mesh = await this.rpc('GetMesh', { mesh_id: session.mesh_id })
      .then(({ info }) => ({ ...fallback, ...info }), () => fallback);
    this.holdMesh(mesh);
    return mesh;
  }

  // Watches a session another user shared with this one: frames only.
  async watch({ session_id: sessionId, settings }) {
    const op = ++this.openOp;
    this.stopStream();
    this.releaseSession();
    if (settings) this.settings = settings;
    const what = `Watching session ${sessionId}`;
    try {
      const session = await this.rpc('GetSession', { session_id: sessionId });
      if (op !== this.openOp || this.closed) return;
      Object.assign(this, { session, volume: null, mesh: null, watching: true });
      this.send({ type: 'opened', session, watching: true });
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
    if (!this.session || this.watching) {
      this.send({ type: 'error', what: 'Refine',
                  message: `Refine: ${this.watching ? 'a watched session is its owner\'s to change'
                                                     : 'open a volume first'}.` });
      return;
    }
    const op = ++this.openOp;
    const what = 'Refining the mesh';
    try {
      this.send({ type: 'progress', step: 'refine', text: `${what} ...` });
      await this.meshRefs.quiet(this.volume.volume_id);
      const done = this.meshRefs.build(this.volume.volume_id);
      const mesh = await this.rpc('RefineMesh', {
        mesh_id: this.mesh.mesh_id, point_mm: pointMm }).finally(done);
      this.holdMesh({ ...mesh, volume_id: this.volume.volume_id });
      if (op !== this.openOp) return;
      const session = await this.openSession(this.volume, mesh);
      if (op !== this.openOp || this.closed) {
        this.closeSession(session, mesh);
        return;
      }
      const [oldSession, oldMesh] = [this.session, this.mesh];
      Object.assign(this, { mesh, session });
      this.send({ type: 'refined', mesh, session, point_mm: pointMm });
      this.startStream();
      this.closeSession(oldSession, oldMesh);
    } catch (err) {
      if (op === this.openOp) this.fail(what, err);
    }
  }

  // Closes this tab's session (a watched one is its owner's to close) and
  // forgets it.
  releaseSession() {
    if (this.watching) {
      this.closeSession(null);
    } else {
      this.closeSession(this.session, this.mesh);
    }
    Object.assign(this, { session: null, watching: false });
  }

  // CloseSession, then DeleteMesh of `mesh` if this tab built it and no
  // longer shows it (every mesh it built once the tab is gone) and no other
  // tab of this gateway uses it: the server would evict an unused mesh at
  // its cap anyway, but deleting it now brings the server's mesh count back
  // to where it was before the tab came.
  closeSession(session, mesh = null) {
    const closing = session
      ? this.rpc('CloseSession', { session_id: session.session_id })
        .then(() => this.record.closed(session.session_id), (err) => {
          this.log(`CloseSession ${session.session_id}: ${err.details ?? err}`);
          if (isServerDown(err)) this.record.leftOver(session.session_id);
          else this.record.closed(session.session_id);
        })
      : Promise.resolve();
    closing.then(() => {
      if (this.closed) return this.releaseMeshes([...this.builtMeshes.keys()]);
      if (mesh && mesh.mesh_id !== this.mesh?.mesh_id) return this.releaseMeshes([mesh.mesh_id]);
      return undefined;
    });
  }

  // Drops this tab's holds on `ids` and deletes those nobody here uses. A
  // closed session keeps its mesh pinned on the server until its stream has
  // finished (a moment after CloseSession answers): FAILED_PRECONDITION is
  // tried again a few times while still unused here, then left to the
  // server's eviction (another gateway's tab may be using it).
  releaseMeshes(ids) {
    const doomed = [];
    for (const id of ids) {
      const mine = this.builtMeshes.get(id);
      if (!mine) continue;
      this.builtMeshes.delete(id);
      for (let i = 0; i < mine.holds; ++i) this.meshRefs.release(id);
      doomed.push({ id, volumeId: mine.volumeId });
    }
    const attempt = ({ id, volumeId }, left, delayMs) => {
      if (this.meshRefs.inUse(id, volumeId)) return undefined;
      const deleting = this.rpc('DeleteMesh', { mesh_id: id });
      this.meshRefs.deleteStarted(volumeId, deleting);
      return deleting.catch((err) => {
        if (err?.code === GrpcStatus.FAILED_PRECONDITION && left > 0) {
          return new Promise((r) => setTimeout(r, delayMs))
            .then(() => attempt({ id, volumeId }, left - 1, 2 * delayMs));
        }
        if (err?.code !== GrpcStatus.FAILED_PRECONDITION && err?.code !== GrpcStatus.NOT_FOUND) {
          this.log(`DeleteMesh ${id}: ${err.details ?? err}`);
        }
        return undefined;
      });
    };
    return Promise.all(doomed.map((m) => attempt(m, kDeleteMeshRetries, 100)));
  }

  // The server reads the file with the readers of `vpm render --render-tf`;
  // this tab's settings may then ask for it (uploaded_tf).
  async readTransferFunction({ file_name: fileName, text, preset }) {
    try {
      const tf = await this.rpc('ReadTransferFunction', { file_name: fileName, text, preset });
      this.uploadedTf = tf;
      this.send({ type: 'tf', name: tf.name, colors: tf.colors.length,
                  opacities: tf.opacities.length });
      // A stream already rendering with an earlier upload takes this one.
      if (this.settings?.uploaded_tf && this.call && !this.watching) {
        this.call.write({ event: { sequence: this.lastSequence, settings: this.protoSettings() } });
      }
    } catch (err) {
      this.fail(`Reading ${fileName}`, err);
    }
  }

  protoSettings(settings = this.settings) {
    return toProtoSettings(settings, this.uploadedTf);
  }

  // ------------------------------------------------------------ the stream

  startStream() {
    this.stopStream();
    const gen = ++this.streamGen;
    const call = this.watching
      ? this.client.watch({ session_id: this.session.session_id,
                            settings: this.protoSettings() }, this.as)
      : this.client.interact(this.as);
    this.call = call;
    let framed = false;
    call.on('data', (frame) => {
      if (gen !== this.streamGen) return;
      if (!framed) {
        framed = true;
        this.barrenRestarts = 0;
        this.serverUpAgain(true);
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
    if (!this.watching) {
      const sequence = this.lastSequence;
      call.write({ session_id: this.session.session_id,
                   event: { sequence, settings: this.protoSettings() } });
      if (this.camera) call.write({ event: { sequence, camera: this.camera } });
    }
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
    // A watched session that is gone is its owner's to reopen, not this tab's.
    if (err.code === GrpcStatus.PERMISSION_DENIED || err.code === GrpcStatus.UNAUTHENTICATED ||
        (gone && this.watching)) {
      this.accessEnded(err);
      return;
    }
    if (gone) {
      // A restarted server, or an idle session the server expired.
      if (this.session) this.record.closed(this.session.session_id);
      this.session = null;
      this.send({ type: 'session_lost', message: `The session is gone from vpm-server ` +
                  `(${String(err.details ?? '').slice(0, 300)}); reopening.` });
      return;
    }
    // An event the server refused (e.g. a grab outside the volume) ends the
    // stream; the session is intact, so a new stream carries on.
    this.fail('Interaction', err);
    this.barrenRestarts = framed ? 0 : this.barrenRestarts + 1;
    if (this.session && this.barrenRestarts <= kMaxBarrenRestarts) this.startStream();
  }

  // The server ended the stream because this user may no longer see the
  // session (a share revoked, the session closed or deleted by its owner, the
  // token no longer valid): no frame more, no new stream, and the page told.
  accessEnded(err) {
    const session = this.session;
    this.pending = null;
    if (this.watching) {
      Object.assign(this, { session: null, watching: false });
    } else {
      this.releaseSession();
    }
    this.log(`stream ended: ${statusName(err.code)}`);
    this.send({ type: 'access_ended', code: statusName(err.code),
                session_id: session?.session_id ?? '',
                message: explainError(err, 'Viewing this session', this.client.address) });
  }

  event(event) {
    if (this.watching) {
      if (!event.settings && !event.camera) {
        this.send({ type: 'error', what: 'Event',
                    message: 'This session is shared with you to watch; only its owner changes it.' });
      }
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
    this.call.write({ event: event.settings ? { ...event, settings: this.protoSettings(event.settings) }
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
    // The tab's calls still running (a load, a mesh build, an open: on a
    // sign-out too) are cancelled, so the server stops their work now
    // rather than for a tab that is gone; a session an open made anyway is
    // closed by the server (OpenSession answers CANCELLED) or by open().
    for (const call of this.calls) call.cancel();
    this.calls.clear();
    clearTimeout(this.probeTimer);
    this.stopStream();
    this.releaseSession();
    this.client.release(this.as);
  }
}

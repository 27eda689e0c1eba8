// The page: wires the volume picker, the tools and the status line to the
// gateway socket. The browser only shows frames and sends input; every
// server call happens in the gateway. `window.vpmViewer` exposes the state
// (frames, last frame header, peak displacement, errors, the case, the
// last undo's answer, the Studies panel, the last export's summary, the
// uploads) to tests.
import { OrbitCamera } from './camera.js';
import { CasesPanel } from './cases_panel.js';
import { applyCaseView } from './case_view.js';
import { CutControls } from './cut_controls.js';
import { ExportButton } from './export_button.js';
import { FrameStats } from './frame_stats.js';
import { GatewaySocket } from './gateway_socket.js';
import { GrabFollow } from './grab_follow.js';
import { fitCanvas, frameSizeForPane } from './pane_fit.js';
import { PointerTools } from './pointer_tools.js';
import { QualityControl } from './quality_control.js';
import { SliceViews } from './slice_views.js';
import { ServerFiles } from './server_files.js';
import { StudiesPanel } from './studies_panel.js';
import { installUndoKeys } from './undo_keys.js';
import { UploadPanel } from './upload_panel.js';
import { volumeNotesText } from './volume_notes.js';
import { VolumePicker } from './volume_picker.js';
import { StackPicker } from './stack_picker.js';
import { parsePacsSource } from './pacs_source.js';
import { fillShortcutList, installViewKeys } from './view_keys.js';
import { kWindowPresets, presetNameOf, windowPreset } from './window_presets.js';

const $ = (id) => document.getElementById(id);
const canvas = $('frame');
const context = canvas.getContext('2d');
const stats = new FrameStats();

const state = {
  gatewayUp: false,
  serverUp: null,
  intent: null,         // what to (re)open: {source}, {volume_id} or {case_id}
  opening: false,
  openedWithCamera: false,  // the open sent the page's camera (the view carries on)
  caseId: null,         // the case of the session shown (server --state-dir), else null
  caseView: null,       // the kept view of the last case opened afresh (opened.view)
  lastUndo: null,       // the gateway's 'undone' answer, until the next manipulation
  undoAnswers: 0,       // 'undone' answers received (for tests)
  casesListed: 0,       // case lists received (for tests)
  volume: null,
  mesh: null,
  session: null,
  camera: null,         // OrbitCamera of the open volume
  sequence: 0,          // last event sequence sent
  lastHeader: null,     // header of the newest frame received
  framesReceived: 0,
  framesDrawn: 0,
  framesSuperseded: 0,  // received while another waited undrawn: replaced, never drawn
  peakDisplacementMm: 0,
  lastGrabMm: null,
  frameSize: { width: 512, height: 512 },  // the 3D frame asked for: the pane's shape
  errors: [],           // {what, message}
  uploadedTf: null,     // {name, colors, opacities} once the gateway read a file
  lastExport: null,     // ExportDicomSummary of the last Export to PACS
  stats,
};
window.vpmViewer = state;

const casesPanel = new CasesPanel({
  body: $('cases-body'),
  note: $('cases-note'),
  currentCaseId: () => state.caseId,
  open(caseId) {
    studies.forget();
    openIntent({ case_id: caseId });
  },
  rename: (caseId, title) => socket.send({ type: 'rename_case', case_id: caseId, title }),
  remove: (caseId) => socket.send({ type: 'delete_case', case_id: caseId }),
});
state.casesPanel = casesPanel;

// A series the Studies panel loaded opens as a volume of the list does.
const studies = new StudiesPanel({
  $,
  send: (m) => socket.send(m),
  openVolume: (volume) => openIntent({ volume_id: volume.volume_id }),
  onOpen: () => serverFiles.refresh(),
});
state.studies = studies;

// The data root's files (for users allowed to browse it) open as sources.
const serverFiles = new ServerFiles({
  $,
  send: (m) => socket.send(m),
  openSource(source) {
    studies.forget();
    openIntent({ source });
  },
});
state.serverFiles = serverFiles;

// An uploaded volume opens as a volume of the list does.
const uploads = new UploadPanel({
  $,
  say: (text, kind) => showMessage(text, kind),
  openVolume(volume) {
    studies.forget();
    openIntent({ volume_id: volume.volume_id });
    socket.send({ type: 'list' });
  },
});
state.uploads = uploads;

const volumePicker = new VolumePicker({ select: $('volume'), loaded: $('loaded') });

// Another stack of the series shown (planes, echoes, phases): a PACS series loads
// through the Studies panel, a data-root folder opens as a source.
const stackPicker = new StackPicker({
  label: $('stack-pick'),
  select: $('stack'),
  open(source, what) {
    if (parsePacsSource(source)) {
      studies.openSource(source, `stack ${what}`);
    } else {
      studies.forget();
      openIntent({ source });
    }
  },
});

const exporter = new ExportButton({
  e: { button: $('export-pacs'), description: $('export-description'), progress: $('export-progress') },
  send: (m) => socket.send(m),
  say: (text, kind) => showMessage(text, kind),
});

// The Export button follows what is shown: a session of this tab's on a
// PACS series.
function refreshExport() {
  exporter.update({ source: state.volume?.source, session: state.session, watching: false });
}

function showMessage(text, kind = 'info') {
  $('message').textContent = text;
  $('message').title = text;  // the line shows two lines at most
  $('message').dataset.kind = text ? kind : 'none';
}

function setServerState(kind, text) {
  $('server-state').dataset.state = kind;
  $('server-state').textContent = text;
}

const socket = new GatewaySocket({
  url: `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/ws`,
  onOpen() {
    state.gatewayUp = true;
    setServerState('unknown', 'gateway connected');
    if (state.intent) openVolume();
  },
  onClose(delayMs) {
    const wasUp = state.gatewayUp;
    Object.assign(state, { gatewayUp: false, session: null, opening: false });
    uploads.connected(null);
    refreshExport();
    setServerState('down', 'gateway unreachable');
    showMessage(`${wasUp ? 'Lost the connection to' : 'Cannot reach'} the web gateway at ` +
                `${location.host}; retrying in ${(delayMs / 1000).toFixed(1)} s.`, 'error');
    checkSignedIn();
  },
  onMessage,
  onFrame,
});

// The gateway refuses the WebSocket of a browser that is not signed in (or
// whose sign-in ended): back to the sign-in form then.
async function checkSignedIn() {
  try {
    const r = await fetch('/whoami', { cache: 'no-store' });
    if (r.status === 401) {
      location.assign('/login');
      return;
    }
    if (r.ok) $('user').textContent = (await r.json()).user;
  } catch {
    // The gateway is down: the socket keeps retrying.
  }
}
checkSignedIn();

// ------------------------------------------------------------ events out

function sendEvent(event) {
  if (!event.camera && !event.settings) state.lastUndo = null;  // a manipulation: the count moves on
  state.sequence += 1;
  // The slices follow the held grab's tissue (grab_follow.js).
  if (event.grab) grabFollow.grab(state.sequence);
  if (event.drag) grabFollow.drag(event.drag.offset_mm);
  if (event.release) grabFollow.release(Boolean(event.release.keep));
  const message = { ...event, sequence: state.sequence };
  if (socket.send({ type: 'event', event: message })) stats.sent(state.sequence);
  return state.sequence;
}

function settings() {
  const [mode, preset] = $('render').value.split(':');
  const { width, height } = state.frameSize;
  const cut = cuts.settings();
  // The view cut (as `vpm render --cut auto`): on unless a crop box or a
  // clip plane says what to show.
  const viewCut = $('view-cut').checked && !cut.crop && !cut.clip;
  const out = { mode, preset, width, height, overlay: $('overlay').checked,
                slices: slices.specs(), ...cut, view_cut: viewCut, ...quality.settings() };
  if (preset === 'uploaded') Object.assign(out, { preset: undefined, uploaded_tf: true });
  return out;
}

// Opens what the user picked: a volume of the list or a source
// ({volume_id} | {source}), a case ({case_id}), or a series the Studies panel
// loaded ({volume_id}).
function openIntent(intent) {
  applyFrameSize();
  state.intent = intent;
  openVolume();
}

// Opens state.intent. The page's camera goes along when the view carries on
// (the same case again, or the same source): else the server's default view.
function openVolume() {
  const { intent } = state;
  const carryOn = Boolean(state.camera) && (intent.case_id ? intent.case_id === state.caseId
                                                           : intent.source === state.volume?.source);
  const message = intent.case_id ? { type: 'open_case', case_id: intent.case_id }
                                 : { type: 'open', ...intent };
  // Unsent while the gateway is away; its reconnection reopens.
  state.opening = socket.send({ ...message, settings: settings(), sequence: state.sequence,
                                camera: carryOn ? state.camera.toProto() : null });
  state.openedWithCamera = carryOn;
  // The gateway lets the session shown go (or, for the same case, its stream).
  if (state.opening) state.session = null;
}

function undo(action) {
  if (!state.session) return showMessage('Nothing to undo: open a volume or a case first.', 'error');
  return socket.send({ type: 'undo', redo: action === 'redo' });
}
installUndoKeys(document, undo);

function refineAt(pointMm) {
  if (!state.session) return showMessage('Open a volume first.', 'error');
  socket.send({ type: 'refine', point_mm: pointMm });
}

const quality = new QualityControl($('render').closest('label'),
                                   () => state.session && sendEvent({ settings: settings() }));
const slices = new SliceViews({
  canvases: { axial: $('slice-axial'), coronal: $('slice-coronal'), sagittal: $('slice-sagittal') },
  labels: { axial: $('at-axial'), coronal: $('at-coronal'), sagittal: $('at-sagittal') },
  tool: () => tools.tool,
  send: sendEvent,
  keepDrags: () => $('keep-drag').checked,
  onChange: () => settingsChanged(),
  onWindow({ width, level }) {
    $('window-width').value = Math.round(width);
    $('window-level').value = Math.round(level);
    $('window-preset').value = presetNameOf({ width: Math.round(width), level: Math.round(level) });
  },
  onGrab(pointMm) {
    state.lastGrabMm = pointMm;
    $('refine-grab').disabled = false;
  },
});
state.slices = slices;
const grabFollow = new GrabFollow((pointMm) => slices.throughPoint(pointMm));
slices.enabled = $('slices').checked;

const cuts = new CutControls({
  crop: $('crop'),
  cropLo: ['x0', 'y0', 'z0'].map((k) => $(`crop-${k}`)),
  cropHi: ['x1', 'y1', 'z1'].map((k) => $(`crop-${k}`)),
  clipSide: $('clip-side'),
  clipAt: $('clip-at'),
  clipLabel: $('clip-label'),
  clipAdd: $('clip-add'),
  clipKept: $('clip-kept'),
  clipClear: $('clip-clear'),
}, () => settingsChanged());

const tools = new PointerTools({
  canvas,
  camera: () => (state.session ? state.camera : null),
  send: sendEvent,
  onRefine: refineAt,
  onGrab(pointMm) {
    state.lastGrabMm = pointMm;
    $('refine-grab').disabled = false;
  },
  onRefused: (text) => showMessage(text, 'error'),
  keepDrags: () => $('keep-drag').checked,
  onCropPress: (x, y, width, height) => cuts.pressFace(state.camera, x, y, width, height),
  onCropDrag: (dx, dy, width, height) => cuts.dragFace(state.camera, dx, dy, width, height),
  onSlicesAt(pointMm) {
    if (!slices.enabled) {
      $('slices').checked = true;
      slicesToggled();
    }
    slices.throughPoint(pointMm);
  },
});

// ------------------------------------------------------------ messages in

const handlers = {
  hello(m) {
    state.gatewayServer = m.server;
    uploads.connected(m);
  },
  server(m) {
    state.serverUp = m.up;
    if (!m.up) {
      setServerState('down', 'vpm-server down');
      showMessage(m.message, 'error');
      return;
    }
    setServerState('up', `vpm-server ${m.address}`);
    if ($('message').dataset.kind === 'error') showMessage('');
    if (state.intent && !state.session && !state.opening) openVolume();
    socket.send({ type: 'cases' });
    if (studies.isOpen) socket.send({ type: 'pacs_endpoints' });
  },
  volumes(m) { volumePicker.fill(m.volumes); },
  progress(m) { showMessage(m.text, 'info'); },
  opened(m) {
    const sameVolume = state.camera && state.openedWithCamera &&
      m.volume.source === state.volume?.source;
    Object.assign(state, { volume: m.volume, mesh: m.mesh, session: m.session, opening: false });
    // Ids belong to one vpm-server replica: a reopen (the session lost with
    // its replica, the gateway back) loads the volume again from its source,
    // wherever the balancer sends it. An upload has no source to reload.
    if (state.intent?.volume_id && !m.volume.source.startsWith('upload:')) {
      state.intent = { source: m.volume.source };
    }
    enterCase(m.session);
    if (!sameVolume) {
      state.camera = new OrbitCamera(m.volume);
      slices.reset();
      cuts.setVolume(m.volume);
    }
    // A case opened afresh: its kept view, which the stream started with.
    if (m.view) {
      applyCaseView(m.view, { render: $('render'), viewCut: $('view-cut'), slicesBox: $('slices'),
                              windowWidth: $('window-width'), windowLevel: $('window-level'),
                              sliceOverlay: $('slice-overlay'), cuts, slices });
      setLayout();
      state.caseView = m.view;
    }
    state.lastGrabMm = null;
    $('refine-grab').disabled = true;
    setServerState('up', `vpm-server ${state.gatewayServer ?? ''}`);
    showMessage(volumeNotesText(m.volume));  // what the reader corrected or chose, else nothing
    stackPicker.show(m.volume);
    volumePicker.opened(m.volume);
    showMesh();
    studies.opened(m.volume);
    uploads.opened(m.volume);
  },
  refined(m) {
    Object.assign(state, { mesh: m.mesh, session: m.session });
    enterCase(m.session);  // a new session: a new case
    const p = m.point_mm;
    showMessage(`Refined at (${p.x.toFixed(1)}, ${p.y.toFixed(1)}, ${p.z.toFixed(1)}) mm: ` +
                'a new session on the finer mesh, starting from rest.', 'info');
    showMesh();
  },
  stream(m) { state.streamOpen = m.state === 'open'; },
  // The server ended the stream: this user may no longer see the session
  // (its share revoked, closed or deleted by its owner). Nothing reopens it.
  access_ended(m) {
    Object.assign(state, { session: null, intent: null, opening: false, streamOpen: false,
                           caseId: null });
    state.errors.push({ what: 'access', message: m.message });
    tools.cancelGrab();
    slices.cancelGrab();
    showMessage(`${m.message} The view has stopped; open a volume to go on.`, 'error');
  },
  session_lost(m) {
    state.session = null;
    showMessage(m.message, 'info');
    if (state.intent && !state.opening) openVolume();
  },
  tf(m) {
    state.uploadedTf = m;
    let option = $('render').querySelector('option[value="dvr:uploaded"]');
    if (!option) {
      option = document.createElement('option');
      option.value = 'dvr:uploaded';
      $('render').append(option);
    }
    option.textContent = `Uploaded: ${m.name || 'transfer function'}`;
    $('render').value = 'dvr:uploaded';
    showMessage(`Read ${m.name}: ${m.colors} colour and ${m.opacities} opacity points.`, 'info');
    settingsChanged();
  },
  error(m) {
    state.errors.push({ what: m.what, message: m.message, code: m.code });
    if (m.what !== 'Interaction') state.opening = false;
    tools.cancelGrab();
    slices.cancelGrab();
    showMessage(m.message, 'error');
    if (m.case_id && m.case_id === state.intent?.case_id && !state.session) caseOpenFailed(m);
    if (m.what?.startsWith('Opening volume')) {
      studies.viewerFailed(m.message);
      uploads.viewerFailed(m);
    }
  },
  cases(m) {
    casesPanel.show(m);
    state.casesKept = m.kept;
    state.casesListed += 1;
    const current = casesPanel.find(state.caseId);
    if (current) state.caseTitle = current.title;
    refreshStatus();
  },
  case_renamed(m) {
    if (m.case.case_id === state.caseId) state.caseTitle = m.case.title;
    showMessage(`Case ${m.case.case_id} is now "${m.case.title}".`, 'info');
    refreshStatus();
  },
  case_deleted(m) {
    if (m.current) {
      Object.assign(state, { session: null, intent: null, opening: false, caseId: null,
                             streamOpen: false });
      tools.cancelGrab();
      slices.cancelGrab();
    }
    showMessage(`Deleted case ${m.case_id}.${m.current ? ' The view has stopped; open a volume ' +
                'or a case to go on.' : ''}`, 'info');
    refreshStatus();
  },
  undone(m) {
    if (m.case_id !== state.caseId) return;
    state.lastUndo = m;
    state.undoAnswers += 1;
    const verb = m.redo ? 'Redo' : 'Undo';
    showMessage(m.changed
      ? `${verb}: ${m.events} events in effect, ${m.undone} undone; largest displacement ` +
        `${m.max_displacement_mm.toFixed(2)} mm.`
      : `${verb}: nothing to ${m.redo ? 'redo' : 'undo'}.`, 'info');
    refreshStatus();
  },
  // The Studies panel (studies_panel.js) and the Export button (export_button.js).
  pacs_endpoints(m) { studies.showEndpoints(m); },
  pacs_studies(m) { studies.showStudies(m); },
  pacs_series(m) { studies.showSeries(m); },
  pacs_progress(m) { studies.showProgress(m); },
  pacs_thumbnail(m) { studies.showThumbnail(m); },
  data_listing(m) { serverFiles.show(m); },
  data_error(m) {
    state.errors.push({ what: 'Server files', message: m.message, code: m.code });
    serverFiles.failed(m);
  },
  pacs_loaded(m) {
    studies.loaded(m);
    socket.send({ type: 'list' });
  },
  pacs_error(m) {
    state.errors.push({ what: `PACS ${m.action}`, message: m.message, code: m.code });
    if (m.action === 'export') exporter.failed(m);
    else studies.failed(m);
  },
  export_progress(m) { exporter.progress(m); },
  upload_progress(m) { uploads.serverProgress(m); },
  exported(m) {
    exporter.done(m);
    state.lastExport = m.summary;
  },
};

// The session shown is on a case (a server with --state-dir): a lost
// session or a gateway back reopens that case, with its deformation.
function enterCase(session) {
  const caseId = session?.case_id || null;
  if (caseId !== state.caseId) Object.assign(state, { lastUndo: null, caseTitle: null });
  state.caseId = caseId;
  if (caseId) state.intent = { case_id: caseId };
  casesPanel.render();
  socket.send({ type: 'cases' });
}

// OpenCase failed. A server that keeps no cases (restarted without
// --state-dir) gets the source again, as a new session; a case that is
// gone (deleted) is not reopened; anything else is tried again once the
// server is back.
function caseOpenFailed(m) {
  const source = state.volume?.source;
  if (m.code === 'FAILED_PRECONDITION' && /keeps no cases/.test(m.message) && source &&
      !source.startsWith('upload:')) {
    Object.assign(state, { intent: { source }, caseId: null });
    showMessage(`${m.message} Reopening ${source} as a new session.`, 'error');
    openVolume();
  } else if (m.code === 'NOT_FOUND') {
    Object.assign(state, { intent: null, caseId: null });
    showMessage(`${m.message} Open a volume or a case to go on.`, 'error');
  }
}

function onMessage(m) {
  const handler = handlers[m.type];
  if (handler) handler(m);
  refreshExport();
}

function showMesh() {
  const s = state.mesh?.stats;
  $('mesh-info').textContent = s
    ? `${state.volume.source} · mesh ${state.mesh.mesh_id}: ${s.vertices} vertices ` +
      `(${s.hard} hard, ${s.refined} refined), ${s.tets} tets, h ${s.h_mm.toFixed(1)} mm · ` +
      `session ${state.session.session_id}`
    : '';
  $('mesh-info').title = $('mesh-info').textContent;  // the line may be cut short
}

// ------------------------------------------------------------ frames

let drawing = false;
let waiting = null;  // the newest frame not yet drawn

function onFrame(frame) {
  const h = frame.header;
  stats.frame(h);
  state.lastHeader = h;
  state.framesReceived += 1;
  state.peakDisplacementMm = Math.max(state.peakDisplacementMm, h.max_displacement_mm);
  // The point the server picked for the held grab (the page's own pick is
  // only a guess until then): "Refine at last grab" refines there.
  if (h.grab_point_mm) {
    const [x, y, z] = h.grab_point_mm;
    state.lastGrabMm = { x, y, z };
  }
  grabFollow.frame(h);
  // The server refined the mesh at a grab and swapped it in.
  if (h.mesh_id && state.mesh && h.mesh_id !== state.mesh.mesh_id) {
    state.mesh = { ...state.mesh, mesh_id: h.mesh_id };
    state.meshRefinedAtGrab = true;
    $('mesh-info').textContent = `${state.volume.source} · mesh ${h.mesh_id}, refined at the ` +
      `grab by the server · session ${state.session.session_id}`;
    $('mesh-info').title = $('mesh-info').textContent;
  }
  if (waiting) state.framesSuperseded += 1;  // newest wins: the waiting one is dropped
  waiting = frame;
  if (!drawing) drawNext();
}

async function drawNext() {
  drawing = true;
  while (waiting) {
    const { header, image, slices: sliceImages } = waiting;
    waiting = null;
    try {
      const bitmap = await createImageBitmap(image);
      context.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
      bitmap.close();
      drawCropOutline(header);
      await slices.draw(sliceImages);
      state.framesDrawn += 1;
      showStatus(header);
    } catch (e) {
      showMessage(`A frame could not be decoded: ${e.message}`, 'error');
    }
  }
  drawing = false;
}

// The crop box's edges over the 3D frame, in the frame's own camera (the
// header's size; the canvas may show it scaled).
function drawCropOutline(header) {
  state.cropOutline = [];  // canvas pixels, for tests
  if (!state.camera) return;
  const segments = cuts.outline(state.camera, header.width, header.height);
  if (!segments.length) return;
  const sx = canvas.width / header.width, sy = canvas.height / header.height;
  context.save();
  context.strokeStyle = 'rgb(255, 210, 0)';
  context.lineWidth = 2;
  context.beginPath();
  for (const [x0, y0, x1, y1] of segments) {
    context.moveTo(x0 * sx, y0 * sy);
    context.lineTo(x1 * sx, y1 * sy);
    state.cropOutline.push([x0 * sx, y0 * sy, x1 * sx, y1 * sy]);
  }
  context.stroke();
  context.restore();
}

function showStatus(h) {
  const latency = stats.latencyMs === null ? '-' : stats.latencyMs.toFixed(0);
  $('status').textContent =
    `${stats.fps()} fps · latency ${latency} ms · ${h.width}x${h.height} ` +
    `${(h.bytes / 1024).toFixed(1)} KB ${h.encoding} · ${frameKind(h)}` +
    ` · server ${h.timings.total_ms.toFixed(0)} ms · max displacement ` +
    `${h.max_displacement_mm.toFixed(2)} mm · lag ${(h.lag_mm ?? 0).toFixed(1)} mm · ` +
    `inverted tets ${h.inverted_tets ?? 0} · frame ${h.frame_number}${caseStatus()}`;
}

// What kind of frame the status line names: a rung of the refinement at
// rest (before the still), one cast while moving, or the still.
function frameKind(h) {
  if (h.refine_level > 0) return `refine ${h.refine_level}`;
  return h.interactive ? 'interactive' : 'still';
}

// The case part of the status line: its title and id, and after an undo or
// redo the events in effect and undone (until the next manipulation).
function caseStatus() {
  if (!state.caseId) return '';
  const title = state.caseTitle ? `"${state.caseTitle}" ` : '';
  const u = state.lastUndo;
  return ` · case ${title}(${state.caseId})` +
    (u ? ` · ${u.events} events in effect, ${u.undone} undone` : '');
}

function refreshStatus() {
  if (state.lastHeader) showStatus(state.lastHeader);
}

// ------------------------------------------------------------ controls

// The 3D frame's size for its pane (the Frame setting is its longer side);
// the canvas takes it at once. Returns whether it changed.
function applyFrameSize() {
  const box = canvas.parentElement;
  const size = frameSizeForPane(box.clientWidth, box.clientHeight, Number($('frame-size').value));
  const changed = size.width !== state.frameSize.width || size.height !== state.frameSize.height;
  state.frameSize = size;
  if (canvas.width !== size.width || canvas.height !== size.height) {
    canvas.width = size.width;
    canvas.height = size.height;
  }
  fitCanvas(canvas, box);
  return changed;
}

// The views' layout: the 3D view alone, or with the three slices.
function setLayout() {
  $('views').dataset.layout = slices.enabled ? 'grid' : 'single';
  applyFrameSize();
}

// A pane that changes size (the window, the layout) refits its canvas; the
// 3D pane asks for a frame of its new shape (once per animation frame).
let resizeRequested = false;
const paneObserver = new ResizeObserver((entries) => {
  for (const entry of entries) {
    const c = entry.target.querySelector('canvas');
    if (c !== canvas) fitCanvas(c, entry.target);
    else if (applyFrameSize() && !resizeRequested) {
      resizeRequested = true;
      requestAnimationFrame(() => {
        resizeRequested = false;
        settingsChanged();
      });
    }
  }
});
for (const box of document.querySelectorAll('#views .box')) paneObserver.observe(box);

$('open').addEventListener('click', () => {
  studies.forget();
  openIntent(volumePicker.intent());
});
$('refresh').addEventListener('click', () => socket.send({ type: 'list' }));
for (const input of document.querySelectorAll('input[name="tool"]')) {
  input.addEventListener('change', () => { tools.tool = input.value; });
}
// Settings go with the open message until a session exists.
const settingsChanged = () => state.session && sendEvent({ settings: settings() });
$('render').addEventListener('change', settingsChanged);
$('overlay').addEventListener('change', settingsChanged);
$('view-cut').addEventListener('change', settingsChanged);
function slicesToggled() {
  slices.enabled = $('slices').checked;
  setLayout();
  settingsChanged();
}
$('slices').addEventListener('change', slicesToggled);
const windowChanged = () => {
  const [width, level] = [Number($('window-width').value), Number($('window-level').value)];
  if (!(width > 0) || !Number.isFinite(level)) {
    showMessage('The window needs a width above 0 and a level (HU).', 'error');
    return;
  }
  slices.window = { width, level };
  $('window-preset').value = presetNameOf(slices.window);
  settingsChanged();
};
// A window preset: the fields take its values and the slices its window.
function applyWindowPreset(name) {
  const preset = windowPreset(name);
  if (!preset) return;
  $('window-width').value = preset.width;
  $('window-level').value = preset.level;
  windowChanged();
}
$('window-preset').append(...kWindowPresets.map((p, i) => new Option(
  `${p.label} (W ${p.width} L ${p.level}) [${i + 1}]`, p.name)));
$('window-preset').value = presetNameOf(slices.window);
$('window-preset').addEventListener('change', () => applyWindowPreset($('window-preset').value));
$('window-width').addEventListener('change', windowChanged);
$('window-level').addEventListener('change', windowChanged);
$('slice-overlay').addEventListener('change', () => {
  slices.overlay = $('slice-overlay').checked;
  settingsChanged();
});
// A transfer function from the tools users have: the gateway hands the text
// to vpm-server, which reads it as `vpm render --render-tf` does.
const kMaxTfFileBytes = 60000;
$('tf-file').addEventListener('change', async () => {
  const file = $('tf-file').files[0];
  if (!file) return;
  if (file.size > kMaxTfFileBytes) {
    showMessage(`${file.name} is ${(file.size / 1024).toFixed(0)} KiB; export one preset ` +
                `(at most ${kMaxTfFileBytes / 1000} kB).`, 'error');
    return;
  }
  socket.send({ type: 'tf', file_name: file.name, text: await file.text() });
});
$('frame-size').addEventListener('change', () => {
  applyFrameSize();
  settingsChanged();
});
$('refine-grab').addEventListener('click', () => state.lastGrabMm && refineAt(state.lastGrabMm));
$('reset-tissue').addEventListener('click', () => sendEvent({ reset: {} }));
$('undo').addEventListener('click', () => undo('undo'));
$('redo').addEventListener('click', () => undo('redo'));
$('cases-refresh').addEventListener('click', () => socket.send({ type: 'cases' }));
document.addEventListener('keydown', (e) => {
  if (e.key !== 'F2' || e.ctrlKey || e.altKey || e.metaKey || e.shiftKey) return;
  e.preventDefault();
  studies.toggle();
});
function resetView() {
  if (!state.camera) return;
  state.camera.reset();
  sendEvent({ camera: state.camera.toProto() });
}
$('reset-view').addEventListener('click', resetView);

// Floating panels: Cases, and Keys and help (its list from view_keys.js).
function showPanel(panel, toggle, open) {
  $(panel).hidden = !open;
  $(toggle).setAttribute('aria-expanded', String(open));
}
fillShortcutList($('keys-list'));
$('keys-toggle').addEventListener('click', () => showPanel('keys', 'keys-toggle', $('keys').hidden));
$('keys-close').addEventListener('click', () => showPanel('keys', 'keys-toggle', false));
$('cases-toggle').addEventListener('click', () => {
  const open = $('cases').hidden;
  showPanel('cases', 'cases-toggle', open);
  if (open) socket.send({ type: 'cases' });
});
$('cases-close').addEventListener('click', () => showPanel('cases', 'cases-toggle', false));
document.addEventListener('keydown', (e) => {
  if (e.key !== 'Escape') return;
  showPanel('keys', 'keys-toggle', false);
  showPanel('cases', 'cases-toggle', false);
});

function pickTool(name) {
  const input = document.querySelector(`input[name="tool"][value="${name}"]`);
  input.checked = true;
  tools.tool = name;
}

function toggleBox(id) {
  $(id).checked = !$(id).checked;
  $(id).dispatchEvent(new Event('change'));
}

installViewKeys(document, (action) => {
  const [kind, name] = action.split(':');
  if (kind === 'window') applyWindowPreset(name);
  else if (kind === 'tool') pickTool(name);
  else if (kind === 'reset-view') resetView();
  else if (kind === 'slices') toggleBox('slices');
  else if (kind === 'view-cut') toggleBox('view-cut');
  else if (kind === 'keys') showPanel('keys', 'keys-toggle', $('keys').hidden);
});
setLayout();

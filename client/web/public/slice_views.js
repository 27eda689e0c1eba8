// The three slice panes (axial, coronal, sagittal): the
// slices each frame carries (RenderSettings.slices, Frame.slices) drawn in
// their canvases, and input on them:
//   wheel:        scrolls the slice along its normal, one pixel size
//                 (the smallest voxel spacing) a notch, 5 with Shift,
//                 kept where the plane still meets the volume;
//   Orbit tool:   dragging sets the window (right: wider, down: higher level);
//   Grab tool:    pressing grabs the tissue under the pointer (the point on
//                 the slice plane, from the slice's geometry), moving drags
//                 it within the plane, releasing lets go, as in 3D.
// Planes sit where the first frame put them (through the volume's centre),
// then where the wheel moves them, or through a point (throughPoint: the
// held grab's tissue, followed while it is dragged, or a Shift+click in 3D):
// each names its position (at_mm).
import { fitCanvas } from './pane_fit.js';
import { clampToSlice, planesThrough } from './slice_planes.js';

const kViews = [
  ['axial', 'SLICE_ORIENTATION_AXIAL'],
  ['coronal', 'SLICE_ORIENTATION_CORONAL'],
  ['sagittal', 'SLICE_ORIENTATION_SAGITTAL'],
];
const kWidthPerPixel = 4;   // window width (HU) per CSS pixel of a drag
const kLevelPerPixel = 2;

export class SliceViews {
  // canvases: {axial, coronal, sagittal}; labels: the same, elements whose
  // text names the position; tool(): 'orbit' | 'grab' | 'refine';
  // send(event) -> sequence; onChange(): the slices' settings changed;
  // onWindow({width, level}): a window drag, or the server's window that a
  // frame shows while the user has set none; onGrab(point_mm); keepDrags():
  // whether a release keeps the drag (Shift on release keeps too), as in 3D.
  constructor({ canvases, labels, tool, send, onChange, onWindow, onGrab,
                keepDrags = () => false }) {
    Object.assign(this, { canvases, labels, tool, send, onChange, onWindow, onGrab, keepDrags });
    this.enabled = false;
    // {width, level}, or null: the server's window for the volume (soft
    // tissue W 400 L 40 on CT, the 1st..99th percentile otherwise), which
    // each frame's slice geometry reports and onWindow shows, until the user
    // sets one.
    this.window = null;
    this.overlay = false;
    this.at = {};        // view -> at_mm (world), once known
    this.geometry = {};  // view -> the newest frame's SliceGeometry
    this.gesture = null;
    this.changeRequested = false;
    this.drawn = 0;      // slice images drawn (tests)
    for (const [view] of kViews) {
      const canvas = canvases[view];
      canvas.addEventListener('wheel', (e) => this.wheel(view, e), { passive: false });
      canvas.addEventListener('pointerdown', (e) => this.down(view, e));
      canvas.addEventListener('pointermove', (e) => this.move(e));
      canvas.addEventListener('pointerup', (e) => this.up(e));
      canvas.addEventListener('pointercancel', (e) => this.up(e));
    }
  }

  // RenderSettings.slices for the page's settings ([] when the panes are off).
  specs() {
    if (!this.enabled) return [];
    return kViews.map(([view, orientation]) => ({
      view, orientation, ...(this.window ? { window: { ...this.window } } : {}),
      overlay: this.overlay,
      ...(this.at[view] === undefined ? {} : { at_mm: this.at[view] }),
    }));
  }

  // A case's slices (RenderSettings.slices, case_view.js): the panes show
  // when it had any; the window and overlay are its first slice's, each
  // pane's plane where the slice of its view tag lay. Nothing is sent.
  applyView(specs) {
    this.enabled = specs.length > 0;
    this.at = {};
    const first = specs[0];
    if (first?.window?.width > 0) {
      this.window = { width: first.window.width, level: first.window.level };
    }
    this.overlay = Boolean(first?.overlay);
    for (const s of specs) {
      if (s.view && Number.isFinite(s.at_mm)) this.at[s.view] = s.at_mm;
    }
  }

  // The window the slices show: the user's, else the newest frame's.
  shownWindow() {
    if (this.window) return this.window;
    const g = Object.values(this.geometry).find((x) => x.window?.width > 0);
    return g ? { width: g.window.width, level: g.window.level } : { width: 400, level: 40 };
  }

  // A new volume: planes back to its centre, the window back to its own.
  reset() {
    this.window = null;
    this.at = {};
    this.geometry = {};
  }

  // slices: unpackFrame's [{header, image}].
  async draw(slices) {
    for (const { header, image } of slices) {
      const canvas = this.canvases[header.view];
      if (!canvas) continue;
      const g = header.geometry;
      this.geometry[header.view] = { ...g, width: header.width, height: header.height };
      if (this.at[header.view] === undefined) this.at[header.view] = g.offset_mm;
      if (!this.window && g.window?.width > 0) this.onWindow?.(g.window);
      const bitmap = await createImageBitmap(image);
      if (canvas.width !== header.width || canvas.height !== header.height) {
        canvas.width = header.width;
        canvas.height = header.height;
        fitCanvas(canvas, canvas.parentElement);
      }
      canvas.getContext('2d').drawImage(bitmap, 0, 0);
      bitmap.close();
      this.drawn += 1;
      this.labels[header.view].textContent = `${g.offset_mm.toFixed(1)} mm`;
    }
  }

  // Moves the planes through pointMm ({x, y, z}, world LPS mm), each kept
  // where it still meets the volume. A move under a tenth of a slice pixel
  // is not sent. Returns whether any plane moved.
  throughPoint(pointMm) {
    const want = planesThrough(pointMm);
    let moved = false;
    for (const [view] of kViews) {
      const g = this.geometry[view];
      const at = clampToSlice(want[view], g);
      if (!Number.isFinite(at)) continue;
      const old = this.at[view];
      if (old !== undefined && Math.abs(old - at) < 0.1 * (g?.pixel_mm ?? 1)) continue;
      this.at[view] = at;
      moved = true;
    }
    if (moved && this.enabled) this.changed();
    return moved;
  }

  wheel(view, e) {
    const g = this.geometry[view];
    if (!this.enabled || !g) return;
    e.preventDefault();
    const notches = Math.sign(e.deltaY) * (e.shiftKey ? 5 : 1);
    const at = (this.at[view] ?? g.offset_mm) + notches * g.pixel_mm;
    this.at[view] = Math.min(g.max_offset_mm, Math.max(g.min_offset_mm, at));
    this.changed();
  }

  // The slice pixel under a pointer event.
  pixel(view, e) {
    const canvas = this.canvases[view];
    const r = canvas.getBoundingClientRect();
    return [((e.clientX - r.left) * canvas.width) / r.width,
            ((e.clientY - r.top) * canvas.height) / r.height];
  }

  down(view, e) {
    const g = this.geometry[view];
    if (!this.enabled || !g || e.button !== 0 || this.gesture) return;
    const [x, y] = this.pixel(view, e);
    const tool = this.tool();
    if (tool === 'grab') {
      // World LPS, as Grab.point_mm: pixel centres of the slice.
      const p = [0, 1, 2].map((k) => g.origin_mm[k] + x * g.step_u_mm[k] + y * g.step_v_mm[k]);
      const point = { x: p[0], y: p[1], z: p[2] };
      this.send({ grab: { point_mm: point } });
      this.onGrab(point);
    } else if (tool !== 'orbit') {
      return;
    }
    const canvas = this.canvases[view];
    canvas.setPointerCapture(e.pointerId);
    this.gesture = { kind: tool, view, canvas, startX: x, startY: y,
                     clientX: e.clientX, clientY: e.clientY, window: { ...this.shownWindow() } };
  }

  move(e) {
    const s = this.gesture;
    if (!s) return;
    if (s.kind === 'orbit') {
      this.window = {
        width: Math.max(1, s.window.width + (e.clientX - s.clientX) * kWidthPerPixel),
        level: s.window.level + (e.clientY - s.clientY) * kLevelPerPixel,
      };
      this.onWindow(this.window);
      this.changed();
      return;
    }
    const g = this.geometry[s.view];
    const [x, y] = this.pixel(s.view, e);
    const [dx, dy] = [x - s.startX, y - s.startY];
    const o = [0, 1, 2].map((k) => dx * g.step_u_mm[k] + dy * g.step_v_mm[k]);
    this.queued = { drag: { offset_mm: { x: o[0], y: o[1], z: o[2] } } };
    this.later();
  }

  up(e) {
    const s = this.gesture;
    if (!s) return;
    this.gesture = null;
    if (s.canvas.hasPointerCapture(e.pointerId)) s.canvas.releasePointerCapture(e.pointerId);
    this.flush();
    if (s.kind === 'grab') this.send({ release: { keep: Boolean(e.shiftKey || this.keepDrags()) } });
  }

  // The server refused the grab: forget the gesture.
  cancelGrab() {
    if (this.gesture?.kind === 'grab') this.gesture = null;
    this.queued = null;
  }

  // Settings and drags go at most once per animation frame.
  changed() {
    this.changePending = true;
    this.later();
  }

  later() {
    if (this.changeRequested) return;
    this.changeRequested = true;
    requestAnimationFrame(() => {
      this.changeRequested = false;
      this.flush();
    });
  }

  flush() {
    if (this.changePending) {
      this.changePending = false;
      this.onChange();
    }
    if (this.queued) {
      const event = this.queued;
      this.queued = null;
      this.send(event);
    }
  }
}

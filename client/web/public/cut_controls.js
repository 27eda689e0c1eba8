// What the 3D view shows of the volume (RenderSettings.crop and .clip, world
// LPS mm): a crop box, one range per world axis, and one clip plane that
// keeps the side of a world axis beyond a position. Both start from the
// open volume's world box (VolumeInfo: origin, direction, dims, spacing).
// With the Crop tool, dragging a face of the box in the 3D view moves it
// (crop_drag.js) and the number fields follow.
import { boxOutlineSegments, faceDragMm, moveBoxFace, pickBoxFace } from './crop_drag.js';

const kAxes = ['x', 'y', 'z'];
// The clip plane's choices: keep what lies towards this patient direction.
const kClipSides = {
  L: [1, 0, 0], R: [-1, 0, 0], P: [0, 1, 0], A: [0, -1, 0], S: [0, 0, 1], I: [0, 0, -1],
};
const kClipSideNames = { L: 'left of', R: 'right of', P: 'posterior of', A: 'anterior of',
                         S: 'superior of', I: 'inferior of' };
// The ray caster takes 16 planes, a crop box counting 6 (kMaxClipPlanes).
export const kMaxClipPlanes = 10;

// The volume's world box: [lo, hi] per axis, mm.
export function worldBox(volume) {
  const d = volume.direction?.length === 9 ? volume.direction : [1, 0, 0, 0, 1, 0, 0, 0, 1];
  const s = volume.spacing_mm ?? { x: 1, y: 1, z: 1 };
  const o = volume.origin_lps_mm ?? { x: 0, y: 0, z: 0 };
  const extent = [0, 1, 2].map((a) => (Number(volume.dims[a]) - 1) * [s.x, s.y, s.z][a]);
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let c = 0; c < 8; ++c) {
    const p = [c & 1 ? extent[0] : 0, c & 2 ? extent[1] : 0, c & 4 ? extent[2] : 0];
    for (let r = 0; r < 3; ++r) {
      const w = [o.x, o.y, o.z][r] + d[r] * p[0] + d[3 + r] * p[1] + d[6 + r] * p[2];
      lo[r] = Math.min(lo[r], w);
      hi[r] = Math.max(hi[r], w);
    }
  }
  return { lo, hi };
}

// A kept plane's words: "left of 12.0" for a plane across a world axis,
// else its normal and offset.
function clipLabel(plane) {
  const n = [plane.normal.x, plane.normal.y, plane.normal.z];
  const side = Object.keys(kClipSides).find((key) => kClipSides[key].every((v, a) => v === n[a]));
  if (side) {
    const a = n.findIndex((v) => v !== 0);
    return `${kClipSideNames[side]} ${(plane.offset_mm / n[a]).toFixed(1)}`;
  }
  return `plane (${n.map((v) => v.toFixed(2)).join(', ')}) at ${plane.offset_mm.toFixed(1)}`;
}

export class CutControls {
  // elements: {crop (checkbox), cropLo: [3 inputs], cropHi: [3 inputs],
  // clipSide (select: '' or a key of kClipSides), clipAt (range input),
  // clipLabel, clipAdd (button: keep the plane, place another), clipKept
  // (output: the kept planes), clipClear (button)}; onChange(): the
  // settings changed. Kept planes and the one being placed all cut.
  constructor(elements, onChange) {
    Object.assign(this, { e: elements, onChange });
    this.box = null;
    const inputs = [elements.crop, ...elements.cropLo, ...elements.cropHi, elements.clipAt];
    for (const input of inputs) input.addEventListener('change', () => this.changed());
    // Moving the slider: at most one settings event per animation frame.
    elements.clipAt.addEventListener('input', () => {
      if (this.inputPending) return;
      this.inputPending = true;
      requestAnimationFrame(() => {
        this.inputPending = false;
        this.changed();
      });
    });
    elements.clipSide.addEventListener('change', () => {
      this.placeClipRange();
      this.changed();
    });
    this.keptClips = [];  // [{plane: ClipPlane message, label}]
    elements.clipAdd.addEventListener('click', () => this.keepClip());
    elements.clipClear.addEventListener('click', () => {
      this.keptClips = [];
      this.showKept();
      this.changed();
    });
    this.showKept();
  }

  // The plane being placed ({normal, offset_mm}, world mm), or null.
  currentClip() {
    const n = kClipSides[this.e.clipSide.value];
    const at = Number(this.e.clipAt.value);
    if (!this.box || !n || !Number.isFinite(at)) return null;
    // Keeps dot(n, x) >= offset: the plane at `at` on its axis.
    const a = n.findIndex((v) => v !== 0);
    return { normal: { x: n[0], y: n[1], z: n[2] }, offset_mm: n[a] * at };
  }

  // Add plane: the plane being placed is kept, the side goes back to
  // "everything" for the next one.
  keepClip() {
    const plane = this.currentClip();
    if (!plane || this.keptClips.length + 1 >= kMaxClipPlanes) return;
    const label = `${kClipSideNames[this.e.clipSide.value]} ${Number(this.e.clipAt.value).toFixed(1)}`;
    this.keptClips.push({ plane, label });
    this.e.clipSide.value = '';
    this.showKept();
    this.changed();
  }

  showKept() {
    const n = this.keptClips.length;
    this.e.clipKept.textContent = n ? `kept: ${this.keptClips.map((k) => k.label).join('; ')} mm` : '';
    this.e.clipClear.hidden = n === 0;
    this.e.clipAdd.disabled = n + 1 >= kMaxClipPlanes;
  }

  // A new volume: the box and the clip range follow its world box.
  setVolume(volume) {
    this.volume = volume;
    this.box = worldBox(volume);
    this.keptClips = [];
    this.showKept();
    kAxes.forEach((_, a) => {
      for (const [inputs, values] of [[this.e.cropLo, this.box.lo], [this.e.cropHi, this.box.hi]]) {
        Object.assign(inputs[a], { min: this.box.lo[a].toFixed(1), max: this.box.hi[a].toFixed(1),
                                   value: values[a].toFixed(1) });
      }
    });
    this.placeClipRange();
  }

  // A case's crop box ({lo_mm, hi_mm} or null) and clip planes ([{normal,
  // offset_mm}], world mm) as the controls' own (case_view.js): the box in
  // the fields, exactly, the planes kept; nothing is sent.
  applyView(crop, clip) {
    this.e.crop.checked = Boolean(crop);
    if (crop) {
      kAxes.forEach((k, a) => {
        this.e.cropLo[a].value = String(crop.lo_mm[k]);
        this.e.cropHi[a].value = String(crop.hi_mm[k]);
      });
    }
    this.e.clipSide.value = '';
    this.keptClips = clip.slice(0, kMaxClipPlanes - 1)
      .map((plane) => ({ plane, label: clipLabel(plane) }));
    this.showKept();
  }

  placeClipRange() {
    const side = kClipSides[this.e.clipSide.value];
    if (!this.box || !side) return;
    const a = side.findIndex((v) => v !== 0);
    Object.assign(this.e.clipAt, { min: this.box.lo[a], max: this.box.hi[a], step: 0.5,
                                   value: (this.box.lo[a] + this.box.hi[a]) / 2 });
  }

  // The crop box the fields hold ({lo, hi}, world mm), or null.
  cropBox() {
    if (!this.box) return null;
    const read = (inputs) => inputs.map((i) => Number(i.value));
    const [lo, hi] = [read(this.e.cropLo), read(this.e.cropHi)];
    if (!lo.every(Number.isFinite) || !hi.every(Number.isFinite)) return null;
    return { lo: lo.map((v, a) => Math.min(v, hi[a])), hi: hi.map((v, a) => Math.max(v, lo[a])) };
  }

  // The Crop tool pressed frame pixel (px, py): true when it is on a face
  // of the box, which the following dragFace calls move.
  pressFace(camera, px, py, width, height) {
    const box = this.cropBox();
    const face = box && pickBoxFace(camera, this.volume, box, px, py, width, height);
    this.faceDrag = face ? { face, start: box } : null;
    return Boolean(face);
  }

  // The pointer moved (dx, dy) frame pixels from the press: the face moves
  // along its normal, the fields follow, the crop turns on; settings go at
  // most once per animation frame.
  dragFace(camera, dx, dy, width, height) {
    const d = this.faceDrag;
    if (!d) return;
    const delta = faceDragMm(camera, this.volume, d.face, dx, dy, width, height);
    const moved = moveBoxFace(d.start, d.face, delta, this.box);
    const inputs = d.face.high ? this.e.cropHi : this.e.cropLo;
    const values = d.face.high ? moved.hi : moved.lo;
    inputs[d.face.axis].value = values[d.face.axis].toFixed(1);
    this.e.crop.checked = true;
    if (this.inputPending) return;
    this.inputPending = true;
    requestAnimationFrame(() => {
      this.inputPending = false;
      this.changed();
    });
  }

  // The crop box's outline on a width x height frame (segments of
  // boxOutlineSegments), or [] when the crop is off.
  outline(camera, width, height) {
    const box = this.e.crop.checked ? this.cropBox() : null;
    return box && this.volume ? boxOutlineSegments(camera, this.volume, box, width, height) : [];
  }

  changed() {
    const side = this.e.clipSide.value;
    this.e.clipLabel.textContent = side ? `${Number(this.e.clipAt.value).toFixed(1)} mm` : '';
    this.onChange();
  }

  // The crop and clip fields of RenderSettings ({} when both are off).
  settings() {
    const out = {};
    const box = this.e.crop.checked ? this.cropBox() : null;
    if (box) {
      const vec = (v) => ({ x: v[0], y: v[1], z: v[2] });
      out.crop = { lo_mm: vec(box.lo), hi_mm: vec(box.hi) };
    }
    const clip = [...this.keptClips.map((k) => k.plane), this.currentClip()].filter(Boolean);
    if (clip.length) out.clip = clip;
    return out;
  }
}

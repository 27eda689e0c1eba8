// The interactive-quality control (RenderSettings.interactive_quality): how
// frames are cast while the user drags or orbits, speed against sharpness
// (docs/RENDERING.md, "Interactive quality", gives each setting's frame
// rate and PSNR against the still). The page speaks 'auto' | 'fast' |
// 'balanced' | 'sharp'; lib/render_settings.js turns them into the proto's
// names ('auto': UNSPECIFIED, the server's device chooses). The
// control builds its own <select> after `anchor`, so the page's markup
// needs no change, and remembers the choice in localStorage.
export const kInteractiveQualities = [
  {
    value: 'auto',
    label: 'Auto',
    title: 'The server chooses: sharp on a GPU, fast where it renders on CPU cores'
  },
  {value: 'fast', label: 'Fast', title: 'Half resolution, coarse step: the highest frame rate'},
  {
    value: 'balanced',
    label: 'Balanced',
    title: 'Half resolution, a step near the still\'s: sharper, slower'
  },
  {
    value: 'sharp',
    label: 'Sharp',
    title: 'Full resolution, a step near the still\'s: closest to the still, slowest'
  },
];
export const kDefaultInteractiveQuality = 'auto';
const kStorageKey = 'vpm.interactiveQuality';

export class QualityControl {
  // anchor: the element the control follows; onChange(value) on a choice;
  // storage: a localStorage-like object (optional).
  constructor(anchor, onChange, storage = globalThis.localStorage) {
    this.storage = storage;
    const stored = safeGet(storage, kStorageKey);
    this.value = kInteractiveQualities.some((q) => q.value === stored)
      ? stored : kDefaultInteractiveQuality;
    if (!anchor?.ownerDocument) return;
    const doc = anchor.ownerDocument;
    const label = doc.createElement('label');
    label.className = anchor.className;  // a row of the controls column, as its anchor
    label.title = 'Frames while dragging or orbiting; the still follows when you stop';
    label.append('While moving ');
    const select = doc.createElement('select');
    select.id = 'interactive-quality';
    for (const q of kInteractiveQualities) {
      const option = doc.createElement('option');
      option.value = q.value;
      option.textContent = q.label;
      option.title = q.title;
      select.append(option);
    }
    select.value = this.value;
    select.addEventListener('change', () => {
      this.value = select.value;
      safeSet(storage, kStorageKey, this.value);
      onChange?.(this.value);
    });
    label.append(select);
    anchor.after(label);
    this.select = select;
  }

  // What the control adds to the page's settings.
  settings() { return { interactive_quality: this.value }; }
}

function safeGet(storage, key) {
  try { return storage?.getItem(key) ?? null; } catch { return null; }
}

function safeSet(storage, key, value) {
  try { storage?.setItem(key, value); } catch { /* private mode: not kept */ }
}

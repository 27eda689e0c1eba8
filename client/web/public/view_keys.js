// The page's single-key shortcuts and the list the page shows of every
// key and mouse gesture ("?"). Undo and redo are undo_keys.js's; F2 is the
// Studies panel's (app.js). Keys typed into a field (text, number, date,
// ...) stay the field's.

import { takesTyping } from './typing_target.js';
import { kWindowPresets } from './window_presets.js';

// key (KeyboardEvent.key, lower case) -> action.
const kKeyActions = {
  ...Object.fromEntries(kWindowPresets.map((p, i) => [String(i + 1), `window:${p.name}`])),
  r: 'reset-view',
  s: 'slices',
  c: 'view-cut',
  o: 'tool:orbit',
  g: 'tool:grab',
  p: 'tool:pin',
  '?': 'keys',
};

// What the page lists: [keys, what they do].
export const kShortcutList = [
  ...kWindowPresets.map((p, i) => [String(i + 1), `${p.label} window (W ${p.width} L ${p.level})`]),
  ['R', 'Reset view'],
  ['S', 'Slices on / off'],
  ['C', 'Cut to the grab on / off'],
  ['O / G / P', 'Orbit / Grab / Pin tool'],
  ['Ctrl+Z', 'Undo (Cmd+Z)'],
  ['Ctrl+Shift+Z', 'Redo (Ctrl+Y, Cmd+Shift+Z)'],
  ['F2', 'Studies panel'],
  ['?', 'This list'],
  ['Right / middle drag', 'Pan the 3D view'],
  ['Wheel', '3D: zoom about the pointer; slice: scroll (Shift: 5 steps)'],
  ['Shift+click', '3D (Orbit tool): slices through that point'],
];

// e: a KeyboardEvent (or a plain object with its fields). Returns the
// action ('window:NAME', 'reset-view', 'slices', 'view-cut', 'tool:NAME',
// 'keys') or null.
export function viewKey(e) {
  if (e.ctrlKey || e.metaKey || e.altKey || e.repeat) return null;
  const key = String(e.key ?? '').toLowerCase();
  if (e.shiftKey && key !== '?') return null;
  return kKeyActions[key] ?? null;
}

// Calls onAction(action) for those keys pressed anywhere on `target` (the
// document) but in a field that takes typing.
export function installViewKeys(target, onAction) {
  target.addEventListener('keydown', (e) => {
    const action = viewKey(e);
    if (!action || takesTyping(e.target)) return;
    e.preventDefault();
    onAction(action);
  });
}

// Fills `list` (a <dl>) with kShortcutList.
export function fillShortcutList(list, doc = document) {
  list.replaceChildren(...kShortcutList.flatMap(([keys, text]) => {
    const dt = doc.createElement('dt');
    dt.textContent = keys;
    const dd = doc.createElement('dd');
    dd.textContent = text;
    return [dt, dd];
  }));
}
